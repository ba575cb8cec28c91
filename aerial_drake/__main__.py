"""``python -m aerial_drake run FILE.yaml``: same as the ``aerial-drake`` command."""

import sys

from aerial_drake.cli import main

sys.exit(main())
