"""Sample outputs in the docs, produced by running their commands: ``python docs/samples.py [--check] [FILE ...]``.

A sample is a fenced ``text`` block right after a marker comment that names its command::

    <!-- sample: cosim check-machine examples/pokeys_mill/mill.toml -->
    ```text
    $ cosim check-machine examples/pokeys_mill/mill.toml
    examples/pokeys_mill/mill.toml: OK: a pokeys machine with ...
    ```

The script runs every command from the repository root (``cosim ...`` is this Python's ``-m cosim``,
``python ...`` this Python), takes what it printed (stdout, then stderr), makes absolute paths
relative to the root and shows wall-clock times as ``…`` (they differ from run to run), keeps the
first N lines for a command ending ``| head -n N``, and writes it into the block under a ``$``
line with the command. ``--check`` writes nothing: it exits 1 naming each block whose output has
changed (tests/test_doc_samples.py runs it), so a sample in the docs is always what the command
prints today.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: The files whose samples are kept: the README and every page of the docs.
FILES = (ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")))
MARKER = re.compile(r"^<!-- sample: (?P<command>.+?) -->\n```text\n(?P<body>.*?)```\n", re.M | re.S)
WALL = (re.compile(r"(simulated in )\d+(\.\d+)? s"), re.compile(r"(runs in )\d+(\.\d+)? s"))


def run(command: str) -> str:
    """What ``command`` prints, as the docs show it."""
    shown = command
    command, _, head = command.partition(" | head -n ")
    words = shlex.split(command)
    if words[0] == "cosim":
        argv = [sys.executable, "-m", "cosim", *words[1:]]
    elif words[0] == "python":
        argv = [sys.executable, *words[1:]]
    else:
        raise SystemExit(f"docs/samples.py: a sample runs cosim or python, not {words[0]!r}")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p),
               COLUMNS="100")
    with tempfile.TemporaryDirectory(prefix="cosim-samples-") as scratch:
        # an --out folder goes to a scratch folder (shown as given): the checkout gets no results of the samples,
        # which would otherwise make a later `cosim main` refuse its results folder
        outs = {}
        for k, word in enumerate(argv[:-1]):
            if word == "--out":
                outs[argv[k + 1]] = str(Path(scratch) / argv[k + 1])
                argv[k + 1] = outs[argv[k + 1]]
        done = subprocess.run(argv, cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    text = done.stdout + done.stderr
    for given, used in outs.items():
        text = text.replace(used, given)
    text = text.replace(f"{ROOT}/", "").replace(str(ROOT), ".")
    for pattern in WALL:
        text = pattern.sub(r"\1… s", text)
    lines = text.rstrip("\n").splitlines()
    if head:
        lines = lines[:int(head)] + ["..."] * (len(lines) > int(head))
    return "\n".join([f"$ {shown}", *lines]) + "\n"


def refresh(path: Path) -> tuple[str, list[str]]:
    """The file's text with every sample rerun, and the commands whose output changed."""
    text = path.read_text(encoding="utf-8")
    changed: list[str] = []

    def redo(match: re.Match[str]) -> str:
        body = run(match["command"])
        if body != match["body"]:
            changed.append(match["command"])
        return f"<!-- sample: {match['command']} -->\n```text\n{body}```\n"

    return MARKER.sub(redo, text), changed


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="Rerun the sample outputs of the docs (README.md, docs/*.md).")
    parser.add_argument("files", nargs="*", type=Path, help="only these files (default: the README and docs/*.md)")
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 if a sample is out of date")
    args = parser.parse_args(argv)
    stale = []
    for path in [p.resolve() for p in args.files] or list(FILES):
        text, changed = refresh(path)
        stale += [f"{path.relative_to(ROOT)}: {command}" for command in changed]
        if changed and not args.check:
            path.write_text(text, encoding="utf-8")
    for line in stale:
        print(f"{'out of date' if args.check else 'rewrote'}: {line}")
    return 1 if stale and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
