"""MkDocs hooks: the plant readmes of ``fmu_src/`` become pages of the site.

``docs/fmus.md`` links to ``../fmu_src/<Model>/readme.md`` so that the link works when browsing the
repository; on the site those readmes are pages ``fmu_src/<Model>/readme.md`` and the links are
rewritten to them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from mkdocs.structure.files import File, Files


def on_files(files: Files, config: Any) -> Files:
    root = Path(config["config_file_path"]).parent
    for readme in sorted((root / "fmu_src").glob("*/readme.md")):  # the models' and common/'s
        files.append(File.generated(config, f"fmu_src/{readme.parent.name}/readme.md", abs_src_path=str(readme)))
    return files


def on_page_markdown(markdown: str, page: Any, config: Any, files: Files) -> str:
    if "/" not in page.file.src_uri:  # a page at the top of docs/
        return markdown.replace("](../fmu_src/", "](fmu_src/")
    return markdown
