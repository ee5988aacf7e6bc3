"""The scenario, as a file describes it and as the rest of the package trusts it.

- `schema.py`: the schema (`Scenario` and its parts; a robot's kind is a robot file,
  `corobot_drake/robots`);
- `scenario.py`: `load_scenario` and `save_scenario` (and the schema re-exported): the loader
  imports `validate.py`, which imports the schema, and nothing imports back;
- `sensors.py`: the IR sensors' and cameras' configuration and defaults (each registered
  kind, `sensors/registry.KINDS`, gives `Robot` its map of sensors by name);
- `poses.py`: the one pose convention, Drake's schema `Transform`, and its helpers;
- `bounds.py`: every field's allowed values (`Range`, `OneOf`), stated once beside the schema;
- `placement.py`: the start poses against the ground, the world's bodies and each other;
- `validate.py`: the one validation pass `load_scenario` runs on every layer.
"""
