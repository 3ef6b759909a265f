"""The embedded robot: a differential-drive robot simulated in the storey's walls (from the BIM)."""
