"""The blocks of README's generated tables (tools/figures.py)."""
