"""The mapping's ROS 2 rules against rclpy itself: its QoS profiles, and its verdict on topic, node and
namespace names, for rcl's test cases and for a few thousand random names."""

from __future__ import annotations

import json
import random
import subprocess
from pathlib import Path

import pytest
from ros2kit import ros2_env

from airsim_mapper.mapping.qos import PROFILES
from airsim_mapper.mapping.ros2_names import (
    TOPIC_MAX_LENGTH,
    namespace_problem,
    node_name_problem,
    ros2_name_problem,
    topic_problem,
)

pytestmark = pytest.mark.live  # runs rclpy in .venv-ros2
SCRIPT = Path(__file__).resolve().parent / "rclpy_rules.py"
CASES = [
    *("foo", "~", "~/foo", "~foo", "~f", "/~", "foo/~bar", "{foo}_bar", "{1foo}", "{$}", "foo/{bar"),
    *("foo/bar}/baz", "{{bar}_baz}", "123abc", "foo/123bar", "/a//b", "/a/", "/", "a b", "/ns/node"),
    *("_x", "x9", "9x", "/{ns}/foo", "{node}/foo", "{namespace}", "a-b", "/" + "a" * TOPIC_MAX_LENGTH),
    "/" + "a" * (TOPIC_MAX_LENGTH - 1),
    "a" * 256,
]


def random_names(count: int, seed: int = 59) -> list[str]:
    """Short names over the characters the rules are about; names made of pieces that are mostly legal
    (so that about half are taken); some long ones."""
    rng = random.Random(seed)
    alphabet = "ab_0/~{}-. "
    names = ["".join(rng.choice(alphabet) for _ in range(rng.randint(1, 8))) for _ in range(count)]
    pieces = ["a", "b1", "_c", "/", "/", "/", "~", "~/", "{node}", "{ns}", "{x}", "9", "{", "}", "//"]
    weights = [9, 9, 9, 12, 12, 12, 1, 2, 2, 2, 1, 1, 1, 1, 1]
    names += ["".join(rng.choices(pieces, weights, k=rng.randint(1, 6))) for _ in range(count)]
    return names + ["/" + "b" * rng.randint(240, 250) for _ in range(20)]


def rclpy_rules(python: Path, names: list[str]) -> dict:
    result = subprocess.run(
        [str(python), str(SCRIPT)],
        input=json.dumps(names),
        env=ros2_env(0),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


@pytest.fixture(scope="module")
def rclpy_verdicts(ros2_python: Path) -> dict:
    return rclpy_rules(ros2_python, CASES + random_names(3000))


def test_the_profiles_are_rclpys(rclpy_verdicts):
    for name, settings in rclpy_verdicts["profiles"].items():
        qos = PROFILES[name]
        assert [qos.reliability, qos.durability, qos.depth, qos.history] == settings, name


def test_every_name_is_taken_or_refused_as_rclpy_does(rclpy_verdicts):
    wrong = []
    for name, rclpy in rclpy_verdicts["names"].items():
        ours = {
            "topic": topic_problem(name) is None,
            "full": ros2_name_problem(name, "node", "/ns") is None,
            "node": node_name_problem(name) is None,
            "namespace": namespace_problem(name) is None,
        }
        wrong += [(name, key, rclpy[key]) for key in ours if ours[key] != rclpy[key]]
    assert wrong == []
