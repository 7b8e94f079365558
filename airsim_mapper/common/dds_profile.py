"""Fast DDS's profile for the bridge's ROS 2 processes: the shipped one, unless the user chose their own.

Fast DDS's default shared-memory segment is 512 KB, too small for one 1080p frame; a best-effort
subscriber on the same host then receives only a few of a 30 Hz stream. `fastdds_profile.xml` keeps Fast
DDS's builtin transports (shared memory and UDPv4: discovery and other hosts work as before) with a
segment that holds several 1080p frames. Fast DDS reads its profiles when rclpy creates the process's
first participant, so `use_shipped_profile` runs before `rclpy.init`.

The user's choice always wins: a profiles file named in the environment, a `DEFAULT_FASTDDS_PROFILES.xml`
in the working directory (which Fast DDS loads by itself), `FASTDDS_BUILTIN_TRANSPORTS`, or an RMW other
than Fast DDS. Then nothing is set, and the sentence returned says what is in effect.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, MutableMapping
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["PROFILE", "ProfileChoice", "choose_profile", "use_shipped_profile"]

PROFILE = Path(__file__).resolve().with_name("fastdds_profile.xml")
PROFILE_VARIABLE = "FASTDDS_DEFAULT_PROFILES_FILE"
USER_VARIABLES = (PROFILE_VARIABLE, "FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_BUILTIN_TRANSPORTS")
WORKING_DIRECTORY_PROFILE = "DEFAULT_FASTDDS_PROFILES.xml"
SKIP_WORKING_DIRECTORY_PROFILE = "SKIP_DEFAULT_XML_FILE"
FAST_DDS_RMWS = ("rmw_fastrtps_cpp", "rmw_fastrtps_dynamic_cpp")  # RMW_IMPLEMENTATION unset: Fast DDS too


@dataclass(frozen=True)
class ProfileChoice:
    """What the environment should gain (nothing when the user chose), and the sentence to log."""

    said: str
    set: dict[str, str] = field(default_factory=dict)


def choose_profile(environ: Mapping[str, str], cwd: Path) -> ProfileChoice:
    """The shipped profile for a Fast DDS process whose user chose none; else the user's choice, untouched."""
    rmw = environ.get("RMW_IMPLEMENTATION", "")
    if rmw and rmw not in FAST_DDS_RMWS:
        return ProfileChoice(f"Fast DDS profile: none set (RMW_IMPLEMENTATION={rmw} is not Fast DDS)")
    for name in USER_VARIABLES:
        if environ.get(name):
            return ProfileChoice(f"Fast DDS profile: the user's ({name}={environ[name]})")
    local = cwd / WORKING_DIRECTORY_PROFILE
    if environ.get(SKIP_WORKING_DIRECTORY_PROFILE) != "1" and local.is_file():
        return ProfileChoice(f"Fast DDS profile: the user's ({local}, which Fast DDS reads by itself)")
    return ProfileChoice(
        f"Fast DDS profile: airsim-mapper's ({PROFILE}: shared memory with a large segment, UDPv4)",
        {PROFILE_VARIABLE: str(PROFILE)},
    )


def use_shipped_profile(environ: MutableMapping[str, str] | None = None) -> str:
    """Put the shipped profile in this process's environment unless the user chose one (call it before
    rclpy creates a participant); the sentence saying which profile is in effect, for the log."""
    environ = os.environ if environ is None else environ
    choice = choose_profile(environ, Path.cwd())
    environ.update(choice.set)
    return choice.said
