"""``bim-init run``: a whole initialisation session (§3.3.3-3.3.5) on a robot driver."""
