"""Config files are read only when they are regular files, bounded in size, within a timeout, as UTF-8."""

from __future__ import annotations

import os
import socket
import time

import pytest

from airsim_mapper.common import files
from airsim_mapper.common.files import ConfigFileError, read_config_text


def test_a_regular_file_is_read_as_text(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text("version: 1\nname: é\n")
    assert read_config_text(path) == "version: 1\nname: é\n"


def test_a_fifo_is_refused_at_once_instead_of_blocking_for_a_writer(tmp_path):
    fifo = tmp_path / "scene.jsonc"
    os.mkfifo(fifo)
    start = time.monotonic()
    with pytest.raises(ConfigFileError) as err:
        read_config_text(fifo, timeout=5)
    assert time.monotonic() - start < 1
    assert str(err.value) == f"{fifo}: is a FIFO (named pipe), not a regular file"
    assert not err.value.unreadable


def test_a_directory_and_a_socket_are_not_config_files(tmp_path):
    with pytest.raises(ConfigFileError, match=r": is a directory, not a regular file$"):
        read_config_text(tmp_path)
    with socket.socket(socket.AF_UNIX) as sock:
        sock.bind(str(tmp_path / "s"))
        with pytest.raises(ConfigFileError, match=r"/s: (is a socket, not a regular file|No such device)"):
            read_config_text(tmp_path / "s")


def test_a_missing_file_is_unreadable_with_the_systems_reason(tmp_path):
    with pytest.raises(ConfigFileError) as err:
        read_config_text(tmp_path / "nope.yaml")
    assert str(err.value) == f"{tmp_path / 'nope.yaml'}: No such file or directory"
    assert err.value.unreadable
    assert err.value.about("mapping file") == "cannot read the mapping file: No such file or directory"


def test_a_file_over_the_limit_is_refused_before_it_is_read(tmp_path, monkeypatch):
    path = tmp_path / "big.yaml"
    with open(path, "wb") as big:
        big.truncate(files.MAX_CONFIG_BYTES + 1)  # sparse
    monkeypatch.setattr(files.os, "read", lambda *_: pytest.fail("read"))
    with pytest.raises(ConfigFileError) as err:
        read_config_text(path)
    assert err.value.reason == "is 16777217 bytes or more, over the limit of 16777216 bytes for a config file"
    assert err.value.about("scene file") == f"the scene file {err.value.reason}"


def test_a_read_that_hangs_is_given_up_after_the_timeout(tmp_path, monkeypatch):
    monkeypatch.setattr(files, "_read", lambda *_: time.sleep(5))  # a file on a hung file system
    start = time.monotonic()
    with pytest.raises(ConfigFileError) as err:
        read_config_text(tmp_path / "hung.yaml", timeout=0.2)
    assert time.monotonic() - start < 1
    assert err.value.reason == "reading it did not finish within 0.2 s (a hung file system or device?)"
    assert err.value.unreadable


def test_text_that_is_not_utf8_is_located_at_its_first_bad_byte(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_bytes(b"version: 1\nname: caf\xe9\n")
    with pytest.raises(ConfigFileError) as err:
        read_config_text(path)
    assert str(err.value) == f"{path}:2:10: is not UTF-8 text (byte 0xe9)"
    assert (err.value.line, err.value.column, err.value.unreadable) == (2, 10, False)


def test_every_config_read_of_the_package_goes_through_this_module():
    from pathlib import Path

    package = Path(files.__file__).parent
    readers = {
        str(path.relative_to(package))
        for path in package.rglob("*.py")
        if "simserver" not in path.parts
        and any(call in path.read_text() for call in (".read_text(", "open("))
    }
    not_configs = {
        "files.py": "the reader itself",
        "scene.py": "the client's open, for other modes than reading",
        "ros_types.py": "genpy module headers on the Python path",
        "mapping/schema.py": "the package's own schema",
        "tuning.py": "/proc/self/maps",
    }
    assert readers <= set(not_configs), readers
