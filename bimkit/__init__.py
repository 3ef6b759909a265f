"""bimkit: the plumbing both commands share and nothing else (no IFC, no algorithms).

- :mod:`bimkit.errors`: the one exception type for bad input, and the exit codes;
- :mod:`bimkit.limits`: the stated limits on what a command reads (bytes per kind of file, depth,
  digits, the YAML alias budget);
- :mod:`bimkit.documents`: bounded reading of files and of the YAML and JSON documents in them;
- :mod:`bimkit.checks`: validation at every way in (numbers; the readers of :mod:`bimkit.documents`);
- :mod:`bimkit.outputs`: every output path checked against the inputs and the file system first;
- :mod:`bimkit.atomic`: outputs written so that a failure leaves nothing half-written and a rerun
  replaces only what the tool wrote;
- :mod:`bimkit.cli`: option callbacks, the one error line, SIGTERM as Ctrl-C, the console-script runner;
- :mod:`bimkit.schemas`: the JSON Schema of every file format read or written.
"""
