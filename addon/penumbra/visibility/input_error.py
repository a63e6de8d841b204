"""The add-on's own error for bad visibility input: its own module so that
every reader of Blender (mesh, armature, World) and every operator can raise
and catch it without importing one another."""


class VisibilityInputError(ValueError):
    """Bad input the user can fix; the message says how."""
