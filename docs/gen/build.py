"""mkdocs-gen-files script: write every generated page of docgen into the build (``make docs``)."""

from __future__ import annotations

import sys
from pathlib import Path

import mkdocs_gen_files

sys.path.insert(0, str(Path(__file__).resolve().parent))

import docgen  # noqa: E402

for page in docgen.generated_pages():
    data = page.data()
    with mkdocs_gen_files.open(page.path, "wb" if isinstance(data, bytes) else "w") as handle:
        handle.write(data)
    if page.source:
        mkdocs_gen_files.set_edit_path(page.path, Path("..") / page.source)
