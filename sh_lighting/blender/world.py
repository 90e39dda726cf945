"""The 9 lighting coefficients L_lm of a scene's world, as Blender renders it.

Two ways, chosen by reading the world's node tree (nothing is ever written to it):

* **image** (fast, exact for the image): World Output ← Background ← Environment Texture
  (Equirectangular or Mirror Ball), optionally ← Mapping (Point, rotation only) ← Texture
  Coordinate (Generated). The image's pixels are read once and projected by the core; the
  Background's Strength scales L, and a Mapping rotation R gives the lighting of the image
  rotated by R⁻¹ (REFERENCE.md §3; checked against Cycles renders in tests/blender/test_world.py).
  ``Image.pixels`` of a float image (EXR, HDR, 16-bit PNG) are already scene-linear whatever
  the image's colour space; 8-bit images give byte / 255 in their own colour space, so "sRGB"
  ones are decoded with the exact sRGB curve (what Cycles does) and "Non-Color" / "Linear
  Rec.709" ones are used as they are;
* **capture** (anything else: Sky Texture, gradients, mixes, other colour spaces, transparent
  texels, unsupported Mapping settings, ...): the world is rendered by Cycles into an
  equirectangular panorama (``capture.capture_world``) which is projected the same way.

Errors that no rendering can fix (no world, no output, a texture without its image, an image
whose file is missing) raise ``WorldError`` with what to do; nothing in ``bpy.data`` changes.

``world_cache.cached_world_coefficients`` wraps ``world_coefficients`` to reuse its last result
while the world is unchanged.
"""

import time
from dataclasses import dataclass

from ..core.colour import srgb_to_linear
from ..core.mirror_ball import project_mirror_ball
from ..core.projection import project_equirect
from ..core.world_map import apply_mapping
from . import compat
from .capture import CaptureError, capture_world
from .images import has_pixel_data, image_pixels, missing_data_message

PROJECTIONS = ("EQUIRECTANGULAR", "MIRROR_BALL")
# 8-bit colour spaces whose byte / 255 values are already the linear radiance Cycles renders.
LINEAR_BYTE_SPACES = ("Linear Rec.709",)
# Image sources the fast path reads (sequences and movies depend on the frame).
STILL_SOURCES = ("FILE", "GENERATED")


class WorldError(ValueError):
    """The world's lighting cannot be computed; the message says why and what to do."""


@dataclass(frozen=True)
class WorldInfo:
    """How ``world_coefficients`` obtained its result.

    ``source`` is "image" (the Environment Texture's pixels were projected directly) or
    "capture" (the world was rendered by Cycles; ``reason`` says why). For "image":
    ``image`` and ``projection`` name the image and its mapping, ``rotation`` is the Mapping
    node's XYZ Euler rotation in radians (None without a Mapping node) and ``strength`` the
    Background's. ``elapsed`` is the wall time in seconds.
    """

    source: str
    world: str
    elapsed: float
    image: str | None = None
    projection: str | None = None
    rotation: tuple[float, float, float] | None = None
    strength: float | None = None
    reason: str = ""
    capture_width: int | None = None
    cached: bool = False  # reused by ``world_cache``; ``elapsed`` is then the look-up's time


@dataclass(frozen=True)
class _ImagePlan:
    image: object
    projection: str
    rotation: tuple[float, float, float] | None
    strength: float


class _Unsupported(Exception):
    """The node tree is valid but not the simple chain the fast path reads."""


# -- reading the node tree ---------------------------------------------------------------------


def _source_socket(socket):
    """The output socket feeding input ``socket``, through reroutes; None if unlinked.

    Raises _Unsupported for muted or invalid links (what Cycles does with them is not read here).
    """
    while socket.is_linked:
        link = socket.links[0]
        if link.is_muted or not link.is_valid:
            raise _Unsupported(f"the link into '{socket.node.name}' is muted or invalid")
        if link.from_node.type == "REROUTE":
            socket = link.from_node.inputs[0]
            continue
        return link.from_socket
    return None


def _active_output(tree):
    """The World Output Cycles renders: the active one among those targeting Cycles."""
    outputs = [
        node
        for node in tree.nodes
        if node.type == "OUTPUT_WORLD" and not node.mute and node.target in ("ALL", "CYCLES")
    ]
    for node in outputs:
        if node.is_active_output:
            return node
    return outputs[0] if outputs else None


def _upstream_nodes(output):
    """Every node the output depends on (inside node groups too)."""
    seen, stack = set(), [output]
    nodes = []
    while stack:
        node = stack.pop()
        if node.as_pointer() in seen:
            continue
        seen.add(node.as_pointer())
        nodes.append(node)
        for socket in node.inputs:
            for link in socket.links:
                stack.append(link.from_node)
        if node.type == "GROUP" and node.node_tree is not None:
            stack.extend(node.node_tree.nodes)
    return nodes


def _check_images(world, output):
    """WorldError for an image texture without an image, or an image without pixel data."""
    for node in _upstream_nodes(output):
        if node.type not in ("TEX_ENVIRONMENT", "TEX_IMAGE"):
            continue
        kind = "Environment Texture" if node.type == "TEX_ENVIRONMENT" else "Image Texture"
        image = node.image
        if image is None:
            if node.type == "TEX_ENVIRONMENT":
                raise WorldError(
                    f"the {kind} node '{node.name}' of world '{world.name}' has no image: "
                    "open an HDR image in it (World properties > Surface > Color), or remove it"
                )
            continue  # an Image Texture without an image renders black, like Cycles shows
        if image.source in ("FILE", "SEQUENCE", "MOVIE") and not has_pixel_data(image):
            raise WorldError(
                f"world '{world.name}', {kind} '{node.name}': {missing_data_message(image)}"
            )


def _check_world(world, scene_name):
    """The world's active World Output with its Surface connected, or a WorldError."""
    if world is None:
        raise WorldError(
            f"scene '{scene_name}' has no world: add one in Properties > World > New, "
            "then give it an environment (e.g. an HDR image)"
        )
    tree = world.node_tree
    if tree is None or not compat.uses_nodes(world):
        raise WorldError(
            f"world '{world.name}' does not use nodes: click Use Nodes in Properties > World "
            "so that its lighting is described by a node tree"
        )
    output = _active_output(tree)
    if output is None:
        raise WorldError(
            f"world '{world.name}' has no World Output node: add one (Add > Output > World "
            "Output) and connect a Background shader to its Surface input"
        )
    try:
        connected = _source_socket(output.inputs["Surface"]) is not None
    except _Unsupported:
        connected = True  # a muted link: let Cycles show what it makes of it
    if not connected:
        raise WorldError(
            f"the Surface input of World Output '{output.name}' in world '{world.name}' is not "
            "connected, so the world renders black: connect a Background shader to it"
        )
    return output


def _vector_rotation(texture):
    """The Euler rotation the texture's lookup direction is turned by (None: identity)."""
    source = _source_socket(texture.inputs["Vector"])
    if source is None:
        return None
    node = source.node
    if node.mute:
        raise _Unsupported(f"node '{node.name}' is muted")
    if node.type == "TEX_COORD":
        if source.name != "Generated":
            raise _Unsupported(f"the texture uses {source.name} coordinates, not Generated")
        return None
    if node.type != "MAPPING":
        raise _Unsupported(f"the texture's Vector comes from a {node.bl_label} node")
    if node.vector_type != "POINT":
        raise _Unsupported(f"Mapping '{node.name}' is of type {node.vector_type}, not Point")
    inputs = node.inputs
    for name in ("Location", "Rotation", "Scale"):
        if inputs[name].is_linked:
            raise _Unsupported(f"Mapping '{node.name}' has its {name} input linked")
    if any(v != 0.0 for v in inputs["Location"].default_value):
        raise _Unsupported(f"Mapping '{node.name}' has a non-zero Location")
    if any(v != 1.0 for v in inputs["Scale"].default_value):
        raise _Unsupported(f"Mapping '{node.name}' has a Scale other than 1")
    coordinates = _source_socket(inputs["Vector"])
    if coordinates is None or coordinates.node.type != "TEX_COORD" or coordinates.node.mute:
        raise _Unsupported(f"Mapping '{node.name}' is not fed by a Texture Coordinate node")
    if coordinates.name != "Generated":
        raise _Unsupported(f"Mapping '{node.name}' uses {coordinates.name} coordinates")
    return tuple(float(a) for a in inputs["Rotation"].default_value)


def _image_plan(output):
    """The fast-path plan for the world, or _Unsupported saying why it needs a capture."""
    if output.inputs["Volume"].is_linked:
        raise _Unsupported("the world has a volume shader")
    source = _source_socket(output.inputs["Surface"])
    background = source.node
    if background.type != "BACKGROUND" or background.mute:
        raise _Unsupported(f"the world's surface is a {background.bl_label} node")
    strength = background.inputs["Strength"]
    if strength.is_linked:
        raise _Unsupported("the Background's Strength is linked")
    colour = _source_socket(background.inputs["Color"])
    if colour is None:
        raise _Unsupported("the Background has a plain colour")
    texture = colour.node
    if texture.type != "TEX_ENVIRONMENT" or texture.mute or colour.name != "Color":
        raise _Unsupported(f"the Background's Color comes from {texture.bl_label} {colour.name}")
    if texture.projection not in PROJECTIONS:
        raise _Unsupported(f"the Environment Texture's projection is {texture.projection}")
    image = texture.image
    if image.source not in STILL_SOURCES:
        raise _Unsupported(f"image '{image.name}' is a {image.source.lower()}")
    return _ImagePlan(
        image=image,
        projection=texture.projection,
        rotation=_vector_rotation(texture),
        strength=float(strength.default_value),
    )


# -- the two paths -----------------------------------------------------------------------------


def _linear_pixels(image, pixels):
    """Scene-linear RGB(A) of ``pixels`` read from ``image``, or _Unsupported."""
    # Transparent texels: Cycles divides or multiplies by alpha depending on the image's alpha
    # mode and depth; only the cases where it shows the stored colour are read directly.
    alpha_shown_as_is = image.alpha_mode in ("CHANNEL_PACKED", "NONE") or (
        image.is_float and image.alpha_mode == "PREMUL"
    )
    if not alpha_shown_as_is and (pixels[..., 3] < 1.0).any():
        raise _Unsupported(f"image '{image.name}' has transparent texels")
    if image.is_float:
        return pixels
    settings = image.colorspace_settings
    if settings.name == "sRGB":
        return srgb_to_linear(pixels[..., :3])
    if settings.is_data or settings.name in LINEAR_BYTE_SPACES:
        return pixels
    raise _Unsupported(f"8-bit image '{image.name}' is in colour space {settings.name}")


def _project_image(plan, world):
    # ``_check_images`` has made sure a file image has pixels; a generated one always has.
    pixels = image_pixels(plan.image)
    linear = _linear_pixels(plan.image, pixels)
    project = project_equirect if plan.projection == "EQUIRECTANGULAR" else project_mirror_ball
    try:
        coeffs = project(linear)
    except ValueError as error:
        raise WorldError(f"image '{plan.image.name}' of world '{world.name}': {error}") from None
    # The Mapping node turns the lookup direction by R: the lighting is the image turned by Rᵀ.
    return apply_mapping(coeffs, plan.strength, plan.rotation)


def world_coefficients(scene, capture_width=256):
    """(9, 3) float64 L_lm of ``scene``'s world as Cycles renders it, and a ``WorldInfo``.

    ``capture_width``: width of the Cycles panorama when the world has to be rendered.
    Raises WorldError (a ValueError) when the world cannot give any lighting.
    """
    start = time.perf_counter()
    world = scene.world if scene is not None else None
    output = _check_world(world, scene.name if scene is not None else "(none)")
    _check_images(world, output)
    try:
        plan = _image_plan(output)
        coeffs = _project_image(plan, world)
        info = WorldInfo(
            source="image",
            world=world.name,
            elapsed=time.perf_counter() - start,
            image=plan.image.name,
            projection=plan.projection,
            rotation=plan.rotation,
            strength=plan.strength,
        )
        return coeffs, info
    except _Unsupported as why:
        reason = str(why)
    try:
        pixels = capture_world(world, capture_width, frame=scene.frame_current)
    except CaptureError as error:
        raise WorldError(f"world '{world.name}' could not be captured: {error}") from None
    try:
        coeffs = project_equirect(pixels)
    except ValueError as error:
        raise WorldError(
            f"the Cycles capture of world '{world.name}' is not usable: {error}; check the "
            "world's nodes for values that make it render NaN or infinity"
        ) from None
    info = WorldInfo(
        source="capture",
        world=world.name,
        elapsed=time.perf_counter() - start,
        reason=reason,
        capture_width=int(capture_width),
    )
    return coeffs, info

