"""Deciding whether an assembly interlocks: contacts, interlocking matrix, verdicts."""
