"""The lab beside the simulator: what the benchmarks, experiments and docs refresher in
`tools/` compute. Not part of the `corobot_drake` wheel; `tools/setup` puts the checkout on the
venv's path so `import lab` works from the tools and the tests.

- benchmarks: `bench` (real-time factors, fleets), `bench_layers` (physics only, layer by
  layer), `bench_camera`, `bench_ir`, `bench_raycast`, `bench_recording`, `bench_study`,
  `bench_memory` (the server over a long run), `bench_gym`, `camera_cost`, `instructions`
  (callgrind counts);
- experiments: `drive_test` (the book's drive test), `landing` (landing errors), `creep` (a
  robot at rest), `resume_landing` (a command resumed from a saved scene), `step_limit` (the
  coarsest plant step the tyres resolve);
- the hostile corpus of bad inputs (`hostile_inputs`, also run by its test);
- docs: `docs_blocks` (generated blocks), `snapshot` (still pictures).
"""
