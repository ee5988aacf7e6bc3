"""Values a system keeps in its Context's abstract state without Drake copying them."""


class SharedState:
    """A value never changed once made, shared and not copied when Drake clones the Context's
    abstract state (it does so for every update: a deep copy of a growing log, or of a
    300 kB camera frame, at every step would make long runs slow). Subclasses must not be
    mutated after construction."""

    def __deepcopy__(self, memo):
        return self

    def __copy__(self):
        return self
