"""``python -m fhslam.cli``: the ``fhslam`` command."""

import sys

from fhslam.cli import main

sys.exit(main())
