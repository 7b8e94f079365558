"""The Fast DDS profile of the bridge's ROS 2 processes: the shipped one unless the user chose their own."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from airsim_mapper.common.dds_profile import PROFILE, choose_profile, use_shipped_profile

NS = {"p": "http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles"}
FRAME_1080P_DEPTH = 1920 * 1080 * 4  # the largest frame the bridge sends at 1080p: 32FC1


def test_a_fast_dds_process_whose_user_chose_nothing_gets_the_shipped_profile(tmp_path: Path) -> None:
    for environ in ({}, {"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp"}, {"FASTDDS_DEFAULT_PROFILES_FILE": ""}):
        choice = choose_profile(environ, tmp_path)
        assert choice.set == {"FASTDDS_DEFAULT_PROFILES_FILE": str(PROFILE)}
        assert "airsim-mapper's" in choice.said and str(PROFILE) in choice.said


@pytest.mark.parametrize(
    ("environ", "said"),
    [
        (
            {"FASTDDS_DEFAULT_PROFILES_FILE": "/home/u/mine.xml"},
            "FASTDDS_DEFAULT_PROFILES_FILE=/home/u/mine.xml",
        ),
        (
            {"FASTRTPS_DEFAULT_PROFILES_FILE": "/home/u/old.xml"},
            "FASTRTPS_DEFAULT_PROFILES_FILE=/home/u/old.xml",
        ),
        ({"FASTDDS_BUILTIN_TRANSPORTS": "LARGE_DATA"}, "the user's (FASTDDS_BUILTIN_TRANSPORTS=LARGE_DATA)"),
        (
            {"RMW_IMPLEMENTATION": "rmw_cyclonedds_cpp"},
            "RMW_IMPLEMENTATION=rmw_cyclonedds_cpp is not Fast DDS",
        ),
    ],
)
def test_the_users_choice_wins_and_is_named(tmp_path: Path, environ: dict, said: str) -> None:
    choice = choose_profile(environ, tmp_path)
    assert choice.set == {}
    assert said in choice.said


def test_a_profiles_file_fast_dds_reads_from_the_working_directory_is_the_users_unless_skipped(
    tmp_path: Path,
) -> None:
    (tmp_path / "DEFAULT_FASTDDS_PROFILES.xml").write_text("<profiles/>")
    choice = choose_profile({}, tmp_path)
    assert choice.set == {} and str(tmp_path / "DEFAULT_FASTDDS_PROFILES.xml") in choice.said
    assert choose_profile({"SKIP_DEFAULT_XML_FILE": "1"}, tmp_path).set != {}


def test_use_shipped_profile_sets_the_variable_only_when_the_user_chose_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    environ: dict[str, str] = {}
    assert "airsim-mapper's" in use_shipped_profile(environ)
    assert environ == {"FASTDDS_DEFAULT_PROFILES_FILE": str(PROFILE)}
    mine = {"FASTDDS_DEFAULT_PROFILES_FILE": "/home/u/mine.xml"}
    use_shipped_profile(mine)
    assert mine == {"FASTDDS_DEFAULT_PROFILES_FILE": "/home/u/mine.xml"}


def test_the_shipped_profile_is_fast_ddss_builtin_transports_with_a_segment_for_several_1080p_frames() -> (
    None
):
    root = ET.parse(PROFILE).getroot()
    transports = {
        d.findtext("p:transport_id", namespaces=NS): d for d in root.iterfind(".//p:transport_descriptor", NS)
    }
    kinds = sorted(d.findtext("p:type", namespaces=NS) for d in transports.values())
    assert kinds == ["SHM", "UDPv4"]
    shm = next(d for d in transports.values() if d.findtext("p:type", namespaces=NS) == "SHM")
    assert int(shm.findtext("p:segment_size", namespaces=NS)) >= 3 * FRAME_1080P_DEPTH
    participant = root.find("p:participant", NS)
    assert participant is not None and participant.get("is_default_profile") == "true"
    used = [t.text for t in participant.iterfind("p:rtps/p:userTransports/p:transport_id", NS)]
    assert sorted(used) == sorted(transports)
    assert participant.findtext("p:rtps/p:useBuiltinTransports", namespaces=NS) == "false"
