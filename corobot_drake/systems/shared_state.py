"""Values a system keeps in its Context's abstract state without Drake copying them."""


class SharedState:
    """A value never changed once made, shared and not copied when Drake clones the Context's
    abstract state (it does so for every update: a deep copy of a growing log, or of a
    300 kB camera frame, at every step would make long runs slow). Subclasses (frozen
    dataclasses) must not be mutated after construction."""

    def __deepcopy__(self, memo):
        return self

    def __copy__(self):
        return self

    def replace(self, **changes):
        """A copy with the fields in `changes` replaced: `dataclasses.replace` without
        running `__init__` again (a seventh of its cost; the state machines make a few
        every step). Raises TypeError for a name that is not a field."""
        fields = type(self).__dataclass_fields__
        if not changes.keys() <= fields.keys():
            unknown = ", ".join(sorted(changes.keys() - fields.keys()))
            raise TypeError(f"{type(self).__name__} has no field {unknown}")
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.__dict__.update(changes)
        return new
