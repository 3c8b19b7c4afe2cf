"""Exports, pictures and the gallery of generated and verified assemblies."""
