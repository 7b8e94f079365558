"""Errors raised by converters and by the converter registry, all ConvertErrors."""

from __future__ import annotations

from airsim_mapper.common.errors import AirsimMapperError

__all__ = ["ContextError", "ConversionError", "ConvertError", "ConverterNotFound", "OversizedData"]


class ConvertError(AirsimMapperError):
    """The convert layer's base."""


class ConversionError(ConvertError, ValueError):
    """A message could not be converted: missing keys, wrong sizes, non-finite values, unknown encodings.

    The message names the offending field, e.g.
    ``"image: data has 100 bytes, expected 921600 for 640x480 BGR"``.
    """


class OversizedData(ConversionError):
    """A message larger than its bound (an image over ``max_pixels``): dropped and counted as oversized."""


class ConverterNotFound(ConvertError, LookupError):
    """No converter of that name exists in the catalogue."""

    def __init__(self, name: str, suggestions: list[str]) -> None:
        hint = f"; did you mean {' or '.join(repr(s) for s in suggestions)}?" if suggestions else ""
        super().__init__(f"unknown converter {name!r}{hint}")
        self.name = name
        self.suggestions = suggestions


class ContextError(ConvertError, ValueError):
    """A ConvertContext was built with an invalid option value."""
