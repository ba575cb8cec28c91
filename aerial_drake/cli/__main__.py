"""``python -m aerial_drake.cli ...``: same as the ``aerial-drake`` command."""

import sys

from aerial_drake.cli import main

sys.exit(main())
