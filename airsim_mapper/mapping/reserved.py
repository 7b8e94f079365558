"""The ROS names the node owns itself, which no rule may take.

A rule publishing on /diagnostics would put its bytes under the DiagnosticArray type the node's own
publisher registered; a service rule on the node's `~reload_mapping` is refused by ROS at run time. Both
are located errors instead: a literal name at loading, any name at expansion (where the node's name and
namespace are known), so validate-mapping and a live reload refuse the mapping whole.
"""

from __future__ import annotations

from collections.abc import Iterable

# name -> what owns it
GLOBAL = {
    "/diagnostics": "the node's diagnostics (diagnostic_msgs/DiagnosticArray)",
    "/rosout": "ROS logging (rosgraph_msgs/Log)",
    "/rosout_agg": "ROS logging (rosgraph_msgs/Log)",
    "/tf": "tf (tf2_msgs/TFMessage)",
    "/tf_static": "tf (tf2_msgs/TFMessage)",
}
CLOCK = "/clock"
CLOCK_CONVERTER = "clock"
# the node's own service and the two every rospy node has
PRIVATE_SERVICES = ("reload_mapping", "get_loggers", "set_logger_level")


def status_topic(node_name: str) -> str:
    """The status topic (a latched std_msgs/String of JSON) of the node `node_name`, its full ROS name:
    `/airsim_mapper/sim1/bridge/status` for the node /sim1/bridge."""
    return f"/airsim_mapper/{node_name.strip('/')}/status"


def node_names(
    node_name: str, namespace: str = "", clock_rule: bool = False, node_namespace: str = ""
) -> dict[str, str]:
    """Every name the node `node_name` owns (its private names in its ROS namespace, in the root and in
    `namespace`), each with what owns it. /clock is the clock rule's while one is on."""
    owned = dict(GLOBAL)
    if clock_rule:
        owned[CLOCK] = "the clock rule's /clock (rosgraph_msgs/Clock)"
    node = node_name.strip("/")
    for prefix in dict.fromkeys((node_namespace.rstrip("/"), "", namespace.rstrip("/"))):
        for service in PRIVATE_SERVICES:
            owned[f"{prefix}/{node}/{service}"] = f"the node's private service ~{service}"
        owned[status_topic(f"{prefix}/{node}")] = "the node's status topic (std_msgs/String)"
    return owned


def literal_problem(ros: str | None) -> str:
    """Why a rule's literal ROS name (one without templates) is not the rule's to take, or ''."""
    if ros is None or ros not in GLOBAL:
        return ""
    return f"ROS name '{ros}' belongs to {GLOBAL[ros]}; a rule cannot take it"


def clock_rule_on(converters: Iterable[str]) -> bool:
    """Whether any enabled rule (by its converter) publishes the clock."""
    return CLOCK_CONVERTER in set(converters)


def taken_problem(ros: str, converter: str, owned: dict[str, str]) -> str:
    """Why the expanded `ros` of a bridge with `converter` is not its to take, or ''."""
    if ros not in owned or (ros == CLOCK and converter == CLOCK_CONVERTER):
        return ""
    return f"ROS name '{ros}' belongs to {owned[ros]}; a rule cannot take it"
