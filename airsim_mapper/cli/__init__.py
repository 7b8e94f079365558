"""Command-line entry points."""

from __future__ import annotations
