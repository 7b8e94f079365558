"""Every exception the package defines has one root; a subpackage's sit under that subpackage's base."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import pkgutil

import pytest

import airsim_mapper
from airsim_mapper.cli.errors import CliError
from airsim_mapper.common.errors import AirsimMapperError, ConfigError
from airsim_mapper.convert.errors import ConvertError
from airsim_mapper.engine.errors import EngineError
from airsim_mapper.mapping.errors import MappingError
from airsim_mapper.simserver.errors import SimServerError

BASES = {
    "airsim_mapper.cli": CliError,
    "airsim_mapper.convert": ConvertError,
    "airsim_mapper.engine": EngineError,
    "airsim_mapper.mapping": MappingError,
    "airsim_mapper.simserver": SimServerError,
}


# Modules of one ROS flavour only, importable in that flavour's venv (tests/ros2 imports them there).
ROS2_ONLY = frozenset({"airsim_mapper.engine.ros2_link"})
OTHER_FLAVOUR = frozenset() if importlib.util.find_spec("rclpy") else ROS2_ONLY


def defined_exceptions() -> list[type[BaseException]]:
    """Every public exception class defined (not imported) by a module of the package (of this venv's ROS
    flavour)."""
    found = []
    for info in pkgutil.walk_packages(airsim_mapper.__path__, "airsim_mapper."):
        if info.name.endswith("__main__") or info.name in OTHER_FLAVOUR:
            continue
        module = importlib.import_module(info.name)
        found.extend(
            cls
            for _, cls in inspect.getmembers(module, inspect.isclass)
            if issubclass(cls, BaseException)
            and cls.__module__ == info.name
            and not cls.__name__.startswith("_")
        )
    return found


EXCEPTIONS = defined_exceptions()


def test_the_package_defines_its_exceptions_under_one_root():
    assert len(EXCEPTIONS) >= 35
    assert [cls.__qualname__ for cls in EXCEPTIONS if not issubclass(cls, AirsimMapperError)] == []


@pytest.mark.parametrize("cls", EXCEPTIONS, ids=lambda cls: f"{cls.__module__}.{cls.__qualname__}")
def test_each_exception_sits_under_its_subpackages_base(cls):
    for package, base in BASES.items():
        if cls.__module__.startswith(f"{package}."):
            assert issubclass(cls, base), f"{cls.__module__}.{cls.__qualname__} is not a {base.__name__}"


def test_no_two_exceptions_share_a_name_so_a_traceback_says_which_is_meant():
    from airsim_mapper.mapping.scene import SceneConfigError

    assert issubclass(SceneConfigError, ConfigError)
    names = [cls.__name__ for cls in EXCEPTIONS]
    assert sorted({name for name in names if names.count(name) > 1}) == []
