"""A machine as an FMU: ``cosim export-fmu MACHINE.toml -o machine.fmu``.

The machine file's ``[export]`` table names the FMU's outputs and inputs (:mod:`.spec`); the FMU
holds the machine document and a small C entry point (``fmu_src/export/``) that loads the Python
runtime recorded at export time and steps the machine in cosim's integer time (:mod:`.machine`,
:mod:`.runtime`). :func:`export_fmu` writes the FMU (:mod:`.package`). See ``docs/export.md``.
"""
