"""The commands: the main command's stages, their pictures and reports, and the command line (``fsv-bench``)."""
