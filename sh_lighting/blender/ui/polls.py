"""The checks operators share in ``poll``: each says why it fails through poll_message_set."""

from ..data import scene_data

NO_COEFFICIENTS = "No SH coefficients yet: run Compute from World first"


def scene_poll(cls, context):
    """There is an active scene."""
    if context.scene is None:
        cls.poll_message_set("No active scene")
        return False
    return True


NO_WORLD = "The scene has no world: add one in the Scene properties (an HDR image lights best)"


def world_poll(cls, context):
    """There is an active scene and it has a world (Compute from World, Extract Lights)."""
    if not scene_poll(cls, context):
        return False
    if context.scene.world is None:
        cls.poll_message_set(NO_WORLD)
        return False
    return True


def coefficients_poll(cls, context, message=NO_COEFFICIENTS):
    """There is an active scene and it has SH coefficients (else ``message``)."""
    if not scene_poll(cls, context):
        return False
    if not scene_data.has_coefficients(context.scene):
        cls.poll_message_set(message)
        return False
    return True
