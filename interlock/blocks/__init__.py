"""Blocks from deformed fundamental domains, RhomBlocks, and assemblies of them."""
