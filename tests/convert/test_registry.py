"""The registry finds every catalogue converter and explains unknown names."""

from __future__ import annotations

import pytest

from airsim_mapper.convert import registry
from airsim_mapper.convert.catalog import CONVERTERS
from airsim_mapper.convert.errors import ConverterNotFound


@pytest.mark.parametrize("name", sorted(CONVERTERS))
def test_every_catalogue_converter_resolves_to_its_named_function(name):
    function = registry.get(name)
    assert callable(function)
    assert function.__name__ == CONVERTERS[name].function
    assert function.__module__ == f"airsim_mapper.convert.{CONVERTERS[name].module}"


def test_lookups_are_cached():
    assert registry.get("image") is registry.get("image")


def test_unknown_converter_suggests_the_closest_name():
    with pytest.raises(
        ConverterNotFound, match=r"unknown converter 'pointclod'; did you mean 'pointcloud'\?"
    ):
        registry.get("pointclod")


def test_unknown_converter_without_a_close_name_has_no_suggestion():
    with pytest.raises(ConverterNotFound, match=r"^unknown converter 'zzz'$"):
        registry.get("zzz")
