"""Reading configuration files (mappings, scenes, robot configs) without trusting what the path holds.

Every config read goes through `read_config_text`:
- only a regular file is read: a FIFO would block its reader until some writer came, and a directory, a
  socket or a device is no config. The file is opened non-blocking and checked with fstat before any read;
- at most `limit` bytes (16 MiB by default): a larger file is refused before it is read;
- within `timeout` seconds (10 by default): a file on a hung file system or device is given up, and the
  reading thread is left blocked in the kernel (it is a daemon) instead of the caller;
- as UTF-8, with the line and column of the first byte that is not.
"""

from __future__ import annotations

import os
import stat
import threading
from pathlib import Path

from airsim_mapper.common.errors import AirsimMapperError

MAX_CONFIG_BYTES = 16 * 1024 * 1024
READ_TIMEOUT_S = 10.0
CHUNK = 1 << 20
KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
)


class ConfigFileError(AirsimMapperError):
    """A config file that cannot be used as one; str() names the file (and line and column when known).

    `unreadable` is true when the file could not be read at all (missing, no permission, a read that never
    finished), false when it was there but is no config (a directory, a FIFO, too large, not UTF-8)."""

    def __init__(
        self, file: str | Path, reason: str, unreadable: bool, line: int = 0, column: int = 0
    ) -> None:
        self.file, self.reason, self.unreadable = str(file), reason, unreadable
        self.line, self.column = line, column
        where = f"{self.file}:{line}:{column}" if line else self.file
        super().__init__(f"{where}: {reason}")

    def about(self, what: str) -> str:
        """The reason as said of `what` ("mapping file"), without the file name."""
        return f"cannot read the {what}: {self.reason}" if self.unreadable else f"the {what} {self.reason}"


def read_config_text(path: str | Path, limit: int = MAX_CONFIG_BYTES, timeout: float = READ_TIMEOUT_S) -> str:
    """The UTF-8 text of the regular file at `path`, or ConfigFileError (see the module docstring)."""
    data = read_config_bytes(path, limit, timeout)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data.count(b"\n", 0, err.start) + 1
        column = err.start - (data.rfind(b"\n", 0, err.start) + 1) + 1
        reason = f"is not UTF-8 text (byte 0x{data[err.start]:02x})"
        raise ConfigFileError(path, reason, False, line, column) from None


def read_config_bytes(
    path: str | Path, limit: int = MAX_CONFIG_BYTES, timeout: float = READ_TIMEOUT_S
) -> bytes:
    """The bytes of the regular file at `path`, read on a thread of its own within `timeout` seconds."""
    outcome: list[bytes | BaseException] = []
    done = threading.Event()

    def read() -> None:
        try:
            outcome.append(_read(path, limit))
        except BaseException as exc:  # handed to the caller
            outcome.append(exc)
        finally:
            done.set()

    threading.Thread(target=read, name="config-read", daemon=True).start()
    if not done.wait(timeout):
        raise ConfigFileError(
            path, f"reading it did not finish within {timeout:g} s (a hung file system or device?)", True
        )
    result = outcome[0]
    if isinstance(result, BaseException):
        raise result
    return result


def _read(path: str | Path, limit: int) -> bytes:
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)  # a FIFO's open would block
    except OSError as err:
        raise ConfigFileError(path, err.strerror or str(err), True) from None
    try:
        info = os.fstat(fd)
        kind = next((name for test, name in KINDS if test(info.st_mode)), None)
        if not stat.S_ISREG(info.st_mode):
            reason = f"is {kind}, not a regular file" if kind else "is not a regular file"
            raise ConfigFileError(path, reason, False)
        if info.st_size > limit:
            raise ConfigFileError(path, _too_large(info.st_size, limit), False)
        os.set_blocking(fd, True)
        chunks, size = [], 0
        while chunk := os.read(fd, CHUNK):
            size += len(chunk)
            if size > limit:  # it grew after fstat
                raise ConfigFileError(path, _too_large(size, limit), False)
            chunks.append(chunk)
        return b"".join(chunks)
    except OSError as err:
        raise ConfigFileError(path, err.strerror or str(err), True) from None
    finally:
        os.close(fd)


def _too_large(size: int, limit: int) -> str:
    return f"is {size} bytes or more, over the limit of {limit} bytes for a config file"
