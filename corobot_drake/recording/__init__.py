"""A run kept for replay, in Meshcat's and Foxglove's formats.

- `meshcat_html.py`: Drake's Meshcat recording of the run, written as one self-contained HTML
  file with its timeline (`--record FILE.html`, `Simulation.save_recording`);
- `topics.py`: the Foxglove messages of the topics (`corobot_drake.topics` names them and their
  frames, in ROS's conventions, for this and the ROS 2 front end);
- `looks.py`: the schedules and inputs this and the ROS 2 front end share;
- `publishers.py`: the LeafSystems that publish them on periodic events (`add_foxglove_topics`);
- `mcap_log.py`: the topics written to an MCAP file (`--mcap FILE.mcap`);
- `foxglove_live.py`: the topics served live to Foxglove over WebSocket (`--foxglove [PORT]`).
"""
