"""What the tools in `tools/` compute, as package functions: benchmarks (`bench*`,
`camera_cost`; `bench_layers`: physics only layer by layer from the plant alone), system
identification (`sysid`, `drive_tuning`), odometry calibration (`odometry_calibration`), the
tire-grip sweep (`tire_grip`), the drive test and landing errors (`drive_test`, `landing`),
pictures (`snapshot`), the study engine's costs (`bench_study`), the server's memory over a long
run (`bench_memory`), the hostile corpus of bad scenario inputs (`hostile_inputs`, also run by
its test), the plant-step limit (`step_limit`), a resting robot's creep (`creep`), a command
resumed from a saved scene against the uninterrupted one (`resume_landing`) and the docs'
generated blocks (`docs_blocks`). Each tool is argparse over one of these.
"""
