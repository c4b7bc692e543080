"""CLI commands of this area (filled in by its issue)."""

from __future__ import annotations

from typing import Any

__all__ = ["register"]


def register(sub: Any, profile_sub: Any) -> None:
    """Add this area's subcommands."""
