"""Studies: batches of simulation runs (sweeps, Monte-Carlo) on Ray, from one machine to a
cluster.

A study file (`spec.Study`, typed YAML) names a scenario, a grid of parameters, per-run random
draws and the metrics to record, checked whole against its scenario as it loads (`resolve`);
`engine.run_study` expands it into runs, simulates them on Ray workers and writes `runs.csv`,
`summary.md` and plots (`report`). `python -m corobot_drake.study STUDY.yaml` is the command
line.
"""
