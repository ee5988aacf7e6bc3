"""SharedState: the values held in the Context's abstract state."""

import copy
import dataclasses as dc

import pytest

from corobot_drake.systems.drive import CommandRecord, CommandSourceState, DriveRequest
from corobot_drake.systems.motion import ActiveCommand, MotionState


def test_replace_is_dataclasses_replace():
    active = ActiveCommand(3, "drive", 1.0, -1.0, 0.5, (0.1, 0.2, 0.3), 2.0, 0.4)
    states = [active, MotionState(handled_seq=2, active=active),
              CommandRecord(4, "SetPower", 1.5), CommandSourceState(request=DriveRequest(1))]
    for state in states:
        first = dc.fields(state)[0].name
        assert state.replace(**{first: 99}) == dc.replace(state, **{first: 99})
    moved = active.replace(progress=0.25, still_frames=2)
    assert moved == dc.replace(active, progress=0.25, still_frames=2)
    assert (active.progress, active.still_frames) == (0.0, 0)  # the original is unchanged
    assert type(moved) is ActiveCommand and moved is not active


def test_replace_rejects_a_name_that_is_not_a_field():
    with pytest.raises(TypeError, match="ActiveCommand has no field progres"):
        ActiveCommand(3, "drive", 1.0, 1.0, 0.5, (0, 0, 0), 0.0, 0.0).replace(progres=1.0)


def test_a_shared_state_is_never_copied():
    state = MotionState(handled_seq=7)
    assert copy.deepcopy(state) is state and copy.copy(state) is state
