import sys

from corobot_drake.cli import main

sys.exit(main())
