"""Look converters up by catalogue name; implementations are imported lazily and cached."""

from __future__ import annotations

import difflib
import importlib
from collections.abc import Callable
from typing import Any

from airsim_mapper.convert.catalog import CONVERTERS
from airsim_mapper.convert.errors import ConverterNotFound

__all__ = ["get"]

_CACHE: dict[str, Callable[..., Any]] = {}


def get(name: str) -> Callable[..., Any]:
    """The converter function of a catalogue name; ConverterNotFound (with a did-you-mean) otherwise."""
    cached = _CACHE.get(name)
    if cached is not None:
        return cached
    info = CONVERTERS.get(name)
    if info is None:
        raise ConverterNotFound(name, difflib.get_close_matches(str(name), list(CONVERTERS), n=2))
    module = importlib.import_module(f"airsim_mapper.convert.{info.module}")
    function = getattr(module, info.function)
    _CACHE[name] = function
    return function
