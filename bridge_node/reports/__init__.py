"""Plots and tables of the CLI: every matplotlib figure the node writes lives here."""
