"""Which runner runs a bridge: the converter catalogue says (`ConverterInfo.runner`), so adding a converter
never touches the engine."""

from __future__ import annotations

from airsim_mapper.convert import catalog
from airsim_mapper.engine.bridges import Bridge, BridgeParts, MountTransform, SimToRos, StreamingImage
from airsim_mapper.engine.ros_to_sim import RosService, RosToSim
from airsim_mapper.mapping.model import BridgeSpec

__all__ = ["RUNNERS", "build"]

RUNNERS: dict[str, type[Bridge]] = {
    catalog.PUBLISH: SimToRos,
    catalog.STREAM: StreamingImage,
    catalog.SEND: RosToSim,
    catalog.CALL: RosToSim,
    catalog.ACTION: RosToSim,
    catalog.SERVE: RosService,
    catalog.SERVE_ALL: RosService,
}


def build(spec: BridgeSpec, parts: BridgeParts) -> Bridge:
    """The runner the catalogue names for the spec's converter (a static mount's, for `tf: {static}`)."""
    if spec.tf is not None and spec.tf.static:
        return MountTransform(spec, parts)
    return RUNNERS[catalog.CONVERTERS[spec.converter].runner](spec, parts)
