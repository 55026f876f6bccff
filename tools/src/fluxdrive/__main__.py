"""Allow `python -m fluxdrive ...`."""

import sys

from fluxdrive.cli import main

sys.exit(main())
