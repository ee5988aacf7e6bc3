import sys

from corobot_drake.cli import ctrl_c_stops, main

ctrl_c_stops()
sys.exit(main())
