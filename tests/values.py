"""Comparisons for tests that hold both for pure-Python and for mypyc-compiled modules.

Compiled code unboxes floats, so a value that went through a compiled function is equal
to, but not the same object as, the one passed in: compare by value, NaN equal to NaN.
"""

from __future__ import annotations

import math


def same_value(got: object, want: object) -> bool:
    """``got == want``, with NaN equal to NaN (for values echoed in error messages)."""
    if isinstance(got, float) and isinstance(want, float) and math.isnan(want):
        return math.isnan(got)
    return got == want
