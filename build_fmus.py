#!/usr/bin/env python3
"""Build the pantocosim FMUs into ``dist/fmus/``: a thin script over
:mod:`pantocosim.master.fmu.dist` (the same as ``pantocosim build-fmus``).

    python build_fmus.py [--out dist/fmus] [--only NAME ...] [--no-ssp]
"""

import sys

from pantocosim.master.fmu.dist import main

if __name__ == "__main__":
    sys.exit(main())
