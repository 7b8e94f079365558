"""ConvertContext validates its options and never shares mutable defaults."""

from __future__ import annotations

import pytest

from airsim_mapper.convert.context import ConvertContext
from airsim_mapper.convert.errors import ContextError


def test_defaults_are_ned_sim_stamps_and_no_frame():
    ctx = ConvertContext()
    assert (ctx.frame_id, ctx.convention, ctx.stamp, ctx.enu) == ("", "ned", "sim", False)


def test_enu_property_follows_the_convention():
    assert ConvertContext(convention="enu").enu is True


def test_each_context_gets_its_own_state():
    first, second = ConvertContext(), ConvertContext()
    first.state["k"] = 1
    assert "k" not in second.state and not first.mounts


def test_unknown_convention_is_rejected():
    with pytest.raises(ContextError, match=r"convention must be one of \('ned', 'enu'\), got 'nwu'"):
        ConvertContext(convention="nwu")


def test_unknown_stamp_source_is_rejected():
    with pytest.raises(ContextError, match=r"stamp must be one of \('sim', 'ros'\), got 'wall'"):
        ConvertContext(stamp="wall")
