"""An immutable, picklable mapping for parameter values inside frozen dataclasses."""
from __future__ import annotations


class FrozenDict(dict):
    """A read-only dict: hashable, picklable (unlike ``types.MappingProxyType``), and equal to a plain dict."""

    def _readonly(self, *args, **kwargs):
        raise TypeError(f"{type(self).__name__} is read-only")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = __ior__ = _readonly

    def __hash__(self) -> int:
        return hash(tuple(sorted(self.items())))

    def __reduce__(self):
        return (type(self), (dict(self),))
