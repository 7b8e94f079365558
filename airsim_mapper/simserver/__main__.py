"""`python -m airsim_mapper.simserver`: the same as `airsim-mapper-sim`."""

from __future__ import annotations

import sys

from airsim_mapper.simserver.cli import main

sys.exit(main())
