"""``bim-init eval``: the paper's Tables 2 and 3 (§4), reproduced with the baselines beside them."""
