"""`python -m corobot_drake.ros2 list | echo TOPIC | hz TOPIC` (`inspection`)."""

import sys

from corobot_drake.ros2.inspection import main

if __name__ == "__main__":
    sys.exit(main())
