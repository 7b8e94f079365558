"""image_transport's per-topic parameters: `<topic>/jpeg_quality` and the like, read once when a bridge of
the `compressed` or `compressedDepth` transport starts, override the rule's params of that topic.

compressed_image_transport and compressed_depth_image_transport keep their settings in parameters named
after the transport's topic (`<base image topic>/compressed/jpeg_quality`, `.../compressedDepth/depth_max`),
so a launch file written for them configures this bridge too. Each value is checked against the mapping
schema's bounds for that param; one out of them is refused with a message naming the parameter and the
bound, and the rule's own value stays.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from airsim_mapper.convert import image_transport as transport


@dataclass(frozen=True)
class Bound:
    """What a parameter may hold: a number within [low, high] (`above`: strictly above low), or one of
    `choices`."""

    integer: bool = False
    low: float | None = None
    high: float | None = None
    above: bool = False
    choices: tuple[str, ...] = ()

    def refusal(self, value: Any) -> str | None:
        """Why `value` is out of bounds, or None when it is within them."""
        if self.choices:
            return None if value in self.choices else f"one of {', '.join(self.choices)}"
        kind = "an integer" if self.integer else "a number"
        number = isinstance(value, int) or (not self.integer and isinstance(value, float))
        if not number or isinstance(value, bool):
            return kind
        if self.above and value <= self.low:
            return f"{kind} above {self.low:g}"
        if value < self.low or (self.high is not None and value > self.high):
            return f"{kind} from {self.low:g} to {self.high:g}"
        return None


PNG_LEVEL = Bound(integer=True, low=1, high=9)
POSITIVE = Bound(low=0, above=True)
# per converter, the parameters its plugin reads under the transport's topic (the mapping schema's bounds)
TOPIC_PARAMS: dict[str, dict[str, Bound]] = {
    "image_compressed": {
        "format": Bound(choices=transport.FORMATS),
        "jpeg_quality": Bound(integer=True, low=1, high=100),
        "png_level": PNG_LEVEL,
    },
    "image_compressed_depth": {
        "depth_max": POSITIVE,
        "depth_quantization": POSITIVE,
        "png_level": PNG_LEVEL,
    },
}


@dataclass(frozen=True)
class Overridden:
    """A rule's params with the topic's parameters applied, and what was said of the refused ones."""

    params: Mapping[str, Any]
    refused: tuple[str, ...] = ()


def parameter_name(topic: str, param: str) -> str:
    """The ROS parameter the plugin reads for `param` of the transport published on `topic`."""
    return f"{topic.rstrip('/')}/{param}"


def overridden(
    converter: str, topic: str, params: Mapping[str, Any], lookup: Callable[[str], Any]
) -> Overridden:
    """`params` with each of the converter's topic parameters that `lookup` finds (None: not set) in place
    of the rule's value; a value out of bounds is refused and the rule's value kept."""
    names = TOPIC_PARAMS.get(converter)
    if not names:
        return Overridden(params)
    out, refused = dict(params), []
    for param, bound in names.items():
        name = parameter_name(topic, param)
        value = lookup(name)
        if value is None:
            continue
        why = bound.refusal(value)
        if why is None:
            out[param] = value
            continue
        kept = params.get(param, "the converter's default")
        refused.append(f"parameter {name} = {value!r} ignored: it must be {why}; keeping {kept}")
    return Overridden(out, tuple(refused))


def is_topic_parameter(name: str) -> bool:
    """Whether `name` is one of the transports' topic parameters (`.../compressed/jpeg_quality`)."""
    parts = name.rstrip("/").rsplit("/", 2)
    if len(parts) < 3:
        return False
    transports = {"compressed": "image_compressed", "compressedDepth": "image_compressed_depth"}
    converter = transports.get(parts[1])
    return converter is not None and parts[2] in TOPIC_PARAMS[converter]
