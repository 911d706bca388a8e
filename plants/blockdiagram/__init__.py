"""The papers' equation / block-diagram models, written independently of the
bond graphs, to compare against.  Arrives with the seed-plants issue."""
__all__: list[str] = []
