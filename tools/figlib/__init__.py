"""The blocks of the generated tables of docs/results/ (tools/figures.py)."""
