"""The one rule for a name that becomes a file, a folder or an XML attribute (a fleet robot's report folder,
``export-mujoco --body``): letters, digits and ``_ . -``, starting with a letter, digit or ``_`` (never ``.``,
``..`` or an option-like ``-``), at most 64 characters.

Checked with ``fullmatch``: ``re.match(r"^...$")`` lets a trailing newline through (``$`` matches before a final
``\\n``), so ``"r01\\n"`` made a folder beside ``r01`` and ``name="s2r&#10;_left"`` in an MJCF file.
"""

from __future__ import annotations

import re

__all__ = ["NAME_HINT", "NAME_PATTERN", "is_safe_name"]

#: The rule, as a pattern for ``fullmatch`` (never ``match``/``search``).
NAME_PATTERN = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]{0,63}")
#: What to tell the user, for a hint.
NAME_HINT = "letters, digits and _ . - (at most 64, not starting with '.' or '-')"


def is_safe_name(name: object) -> bool:
    """True when ``name`` is a string that follows the rule (the whole string, no trailing newline)."""
    return isinstance(name, str) and NAME_PATTERN.fullmatch(name) is not None
