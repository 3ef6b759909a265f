"""Baseline initialisation methods the paper compares against (§4.3): markers and AMCL."""
