"""Placeholder: filled by the issue that owns it (see sensitivity/__init__.py)."""

__all__: list[str] = []
