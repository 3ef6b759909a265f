"""Plotting and other tools around the core algorithms."""
