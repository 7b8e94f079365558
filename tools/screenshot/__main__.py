"""`python -m tools.screenshot`."""

import sys

from tools.screenshot.screenshot import main

sys.exit(main())
