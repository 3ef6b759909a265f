"""``python -m initcli.config [--write]``: the site config's JSON Schema, printed or written."""

from initcli.config.schema import main

if __name__ == "__main__":
    raise SystemExit(main())
