"""The `vmnav` command line and thin tools around package code."""
