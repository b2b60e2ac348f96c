import sys

from design.cli import main

sys.exit(main())
