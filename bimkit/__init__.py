"""bimkit: the plumbing both commands share and nothing else (no IFC, no algorithms).

- :mod:`bimkit.errors`: the one exception type for bad input, and the exit codes;
- :mod:`bimkit.checks`: validation at every way in (numbers, text, YAML and JSON documents,
  output folders);
- :mod:`bimkit.atomic`: outputs written so that a failure leaves nothing half-written;
- :mod:`bimkit.cli`: option callbacks, the one error line and the console-script runner;
- :mod:`bimkit.schemas`: the JSON Schema of every file format read or written.
"""
