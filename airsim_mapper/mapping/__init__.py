"""The mapping language: load and validate a mapping YAML, and expand its rules over a scene."""

from __future__ import annotations
