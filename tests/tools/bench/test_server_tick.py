"""tools.bench.server_tick times real ticks of the server that send every pose to a subscribed client."""

from __future__ import annotations

from tools.bench import server_tick


def test_every_tick_publishes_each_drones_pose_to_the_subscribed_client_and_is_timed():
    result = server_tick.run(drones=3, ticks=40)
    assert result["drones"] == 3 and 0 < result["p50_ms"] <= result["p99_ms"]
    assert result["us_per_drone"] == 1000.0 * result["p50_ms"] / 3
    # each tick's three poses, after each drone's latest pose, which a subscription is sent first
    assert result["poses_received"] == 3 + 3 * 40
