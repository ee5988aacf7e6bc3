"""The robot as a ROS 2 Jazzy node (`--ros2`) and its topics as rosbag2 recordings (`--rosbag`).

One more front end on the simulation: the topics are published by LeafSystems added to the
station (`publishers`), serialized once as CDR (`messages`, with the `rosbags` type store) and
handed to sinks: the live node's publishers (`node`), a rosbag2 writer (`bag`). Commands come
in through the node (subscription, actions, services) and reach the simulation thread as the
HTTP server's do (`serving.runner.Runner.submit`). Needs the `[ros2]` extra and its interface
packages built (`python -m corobot_drake.ros2.build`, run by tools/setup).
"""
