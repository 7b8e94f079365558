"""The private parts of the pinned libraries that the bridge relies on are still there: each adapter
module (client_internals.py, rospy_internals.py) names them, and a change underneath is reported with the
version the adapter was written against."""

from __future__ import annotations

import pytest

from airsim_mapper.engine import client_internals, rospy_internals
from airsim_mapper.engine.errors import InternalsChanged


@pytest.mark.parametrize("adapter", [client_internals, rospy_internals], ids=lambda m: m.__name__)
def test_the_installed_library_still_has_what_its_adapter_relies_on(adapter) -> None:
    missing = adapter.missing_internals()
    assert not missing, str(InternalsChanged(adapter.PINNED, missing))


def test_a_changed_internal_is_reported_with_the_pinned_version(monkeypatch: pytest.MonkeyPatch) -> None:
    from projectairsim import ProjectAirSimClient

    monkeypatch.delattr(ProjectAirSimClient, client_internals.FRAME_READ)
    missing = client_internals.missing_internals()
    assert missing == [f"ProjectAirSimClient.{client_internals.FRAME_READ}"]
    with pytest.raises(InternalsChanged, match=r"projectairsim 1\.1\.0's internals changed: ProjectAirSim"):
        raise InternalsChanged(client_internals.PINNED, missing)


def test_a_queued_connection_without_its_state_is_reported(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(rospy_internals, "QUEUE_STATE", ("_lock", "_gone"))
    assert rospy_internals.missing_internals() == ["QueuedConnection._gone"]
    assert "Debian 12's rospy" in str(InternalsChanged(rospy_internals.PINNED, ["QueuedConnection._gone"]))
