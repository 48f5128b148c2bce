"""Small helpers shared by the smach modules."""
from __future__ import annotations

from typing import Any, Iterable

__all__ = ["has_smach_interface", "unique_list"]


def has_smach_interface(obj: Any) -> bool:
    """True if ``obj`` declares a smach interface (outcomes and userdata keys), like a State or CBInterface."""
    return all(hasattr(obj, attr) for attr in
               ("get_registered_input_keys", "get_registered_output_keys", "get_registered_outcomes"))


def unique_list(items: Iterable[Any]) -> list:
    """Items in first-seen order without duplicates (sets would make introspection order random)."""
    out: list = []
    for item in items:
        if item not in out:
            out.append(item)
    return out
