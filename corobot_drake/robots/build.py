"""Adds a robot's model to a plant as the station needs it, whatever its file says about
contact and motors: `add_robot_model`.

- the model parsed by Drake's parser from its file and renamed to the scenario's robot name;
- the wheels' collision shapes become the project's compliant-hydroelastic tyres (the
  scenario's `contact`: modulus, mesh size, dissipation, friction);
- the casters' shapes slide with the robot file's caster friction;
- the robot's bodies do not collide with each other;
- one joint actuator per wheel, in wheel order (the drive's desired state's order), with the
  motor's effort limit and Drake's velocity servo (kp = 0, kd = the servo damping); the
  model's own actuators are removed (the wheels are driven by the drive alone).
"""

import numpy as np
from pydrake.geometry import (
    AddCompliantHydroelasticProperties,
    AddContactMaterial,
    CollisionFilterDeclaration,
    ProximityProperties,
    Role,
    RoleAssign,
)
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import PdControllerGains

from corobot_drake.model.sdf import WheelContact
from corobot_drake.resources import make_parser
from corobot_drake.robots.spec import RobotSpec


def add_robot_model(plant: MultibodyPlant, scene_graph, name: str, spec: RobotSpec,
                    contact: WheelContact, visual: str = "meshes"):
    """Parses `spec`'s model into `plant` (not finalized) as the model instance `name`, with
    tyres, casters, self-collision filter and wheel servos (module docstring); `visual`
    `boxes` draws its collision shapes instead of its visuals (`config.schema.Robot.visual`).
    Returns the instance."""
    (instance,) = make_parser(plant).AddModels(str(spec.model_file))
    plant.RenameModelInstance(instance, name)
    if visual == "boxes":
        _collision_looks(plant, scene_graph, instance)
    wheels = [plant.GetJointByName(j, instance) for j in spec.wheel_joints]
    _tyres(plant, scene_graph, [j.child_body() for j in wheels], contact)
    _casters(plant, scene_graph, instance, spec)
    bodies = [plant.get_body(i) for i in plant.GetBodyIndices(instance)]
    scene_graph.collision_filter_manager().Apply(CollisionFilterDeclaration().ExcludeWithin(
        plant.CollectRegisteredGeometries(bodies)))
    # The plant's every actuator, filtered: before Finalize the per-instance list is empty.
    for index in plant.GetJointActuatorIndices():
        actuator = plant.get_joint_actuator(index)
        if actuator.model_instance() == instance:
            plant.RemoveJointActuator(actuator)
    for joint in wheels:
        actuator = plant.AddJointActuator(f"{joint.name()}_motor", joint, contact.effort_limit)
        actuator.set_controller_gains(PdControllerGains(p=0.0, d=contact.servo_damping))
    return instance


COLLISION_LOOK = (0.55, 0.1, 0.1, 1.0)
"""RGBA of a robot's collision shapes drawn as its look (`visual: boxes`)."""


def _collision_looks(plant, scene_graph, instance) -> None:
    """The model's own visuals removed and its collision shapes drawn instead (for Meshcat
    and the cameras alike: the physics view)."""
    inspector = scene_graph.model_inspector()
    for index in plant.GetBodyIndices(instance):
        body = plant.get_body(index)
        for gid in plant.GetVisualGeometriesForBody(body):  # kept, but drawn by no one
            for role in (Role.kIllustration, Role.kPerception):
                if inspector.GetProperties(gid, role) is not None:
                    scene_graph.RemoveRole(plant.get_source_id(), gid, role)
        for k, gid in enumerate(plant.GetCollisionGeometriesForBody(body)):
            plant.RegisterVisualGeometry(body, inspector.GetPoseInFrame(gid),
                                         inspector.GetShape(gid).Clone(),
                                         f"{body.name()}_look_{k}",
                                         np.asarray(COLLISION_LOOK))


def _replace(plant, scene_graph, gid, props: ProximityProperties) -> None:
    scene_graph.AssignRole(plant.get_source_id(), gid, props, RoleAssign.kReplace)


def _tyres(plant, scene_graph, wheel_bodies, contact: WheelContact) -> None:
    """Every collision shape of the wheels: a compliant-hydroelastic tyre."""
    for body in wheel_bodies:
        for gid in plant.GetCollisionGeometriesForBody(body):
            props = ProximityProperties()
            AddContactMaterial(dissipation=contact.hunt_crossley_dissipation,
                               friction=CoulombFriction(contact.friction, contact.friction),
                               properties=props)
            AddCompliantHydroelasticProperties(
                resolution_hint=contact.resolution_hint,
                hydroelastic_modulus=contact.hydroelastic_modulus, properties=props)
            _replace(plant, scene_graph, gid, props)


def _casters(plant, scene_graph, instance, spec: RobotSpec) -> None:
    """The casters' shapes (`spec.casters`, `link/geometry`): their friction."""
    inspector = scene_graph.model_inspector()
    for index in plant.GetBodyIndices(instance):
        body = plant.get_body(index)
        for gid in plant.GetCollisionGeometriesForBody(body):
            if f"{body.name()}/{inspector.GetName(gid).split('::')[-1]}" not in spec.casters:
                continue
            props = ProximityProperties(inspector.GetProximityProperties(gid))
            friction = CoulombFriction(spec.caster_friction, spec.caster_friction)
            if props.HasProperty("material", "coulomb_friction"):
                props.UpdateProperty("material", "coulomb_friction", friction)
            else:
                props.AddProperty("material", "coulomb_friction", friction)
            _replace(plant, scene_graph, gid, props)
