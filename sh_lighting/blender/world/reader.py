"""What a scene's world is, and its 9 lighting coefficients L_lm, as Blender renders it.

``read_world(scene)`` reads the world's node tree as evaluated at the current frame, writes
nothing, and returns an ``ImageSource`` (World Output ← Background ← Environment Texture,
optionally ← Mapping ← Texture Coordinate: the image, its projection, rotation R and Strength
s; the lighting is s × the image's rotated by R⁻¹, docs/reference.md §3) or a
``ProceduralSource`` (anything else, with the reason), which ``world_coefficients`` captures
with Cycles (``capture``). ``WorldError`` for what no render can fix. Coefficients are in the
file's working colour space. Details: docs/modules.md.
"""

import time
from dataclasses import dataclass, field

import bpy

from ...core.equirect import zero_nonfinite
from ...core.mirror_ball import project_mirror_ball
from ...core.projection import project_equirect
from ...core.irradiance import error_estimate
from ...core.world_map import apply_mapping
from ..data import compat
from ..data.node_links import MutedLink, colour_source, source_socket
from .capture import CaptureError, capture_world
from .images import (
    DecodeError,
    has_pixel_data,
    linear_pixels,
    missing_data_message,
    undecodable_reason,
)

PROJECTIONS = ("EQUIRECTANGULAR", "MIRROR_BALL")
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
    Background's (both as evaluated at the scene's frame). ``working_space``: the colour
    space of the coefficients. ``elapsed`` is the wall time in seconds. ``error``: the
    9-term error (mean, max) against the world's brute-force irradiance at ``error_normals``
    normals (``irradiance.error_estimate``), when it was asked for and could be measured (an
    equirect image or a capture with light in every channel), else None. ``radiance``: see
    ``world_coefficients``' ``keep_radiance``.
    """

    source: str
    world: str
    elapsed: float
    working_space: str = "Linear Rec.709"
    image: str | None = None
    projection: str | None = None
    rotation: tuple[float, float, float] | None = None
    strength: float | None = None
    reason: str = ""
    capture_width: int | None = None
    error: tuple[float, float] | None = None
    error_normals: int = 0
    # (pixels, Strength, Mapping Euler or None) as ``world_radiance`` gives them, when
    # ``world_coefficients`` was asked to keep them (else None): the same read serves both.
    radiance: tuple | None = field(default=None, repr=False, compare=False)


@dataclass(frozen=True, eq=False)
class ImageSource:
    """A world that is an Environment Texture image read directly (``read_world``).

    world: the world's name; image: the ``bpy.types.Image`` (the original datablock);
    projection: "EQUIRECTANGULAR" or "MIRROR_BALL"; rotation: the Mapping node's XYZ Euler
    rotation in radians, or None without a Mapping node; strength: the Background's
    Strength (both as evaluated at ``frame``); colour_space: the image's colour space;
    working_space: the file's, that of ``pixels()`` and of the coefficients.
    """

    world: str
    image: object
    projection: str
    rotation: tuple | None
    strength: float
    colour_space: str
    working_space: str
    frame: int
    _pixels: object = field(default=None, repr=False)

    def pixels(self):
        """The image's radiance as Blender renders it (``images.linear_pixels``): a fresh
        float32 (H, W, 4) array, rows top to bottom, scene linear in ``working_space``;
        Strength and rotation are *not* applied. WorldError when the image has no pixel data.
        """
        if self._pixels is not None:
            return self._pixels.copy()
        try:
            return linear_pixels(self.image)
        except ValueError as error:  # no pixel data (read_world checked the decoding)
            raise WorldError(f"world '{self.world}': {error}") from None


@dataclass(frozen=True)
class ProceduralSource:
    """A world ``read_world`` cannot read as an image: Cycles must render (capture) it.

    world: the world's name; reason: why (e.g. "the world's surface is a Mix Shader node").
    """

    world: str
    reason: str


class _Unsupported(Exception):
    """The node tree is valid but not the simple chain the fast path reads."""


# -- reading the node tree ---------------------------------------------------------------------


def _source_socket(socket):
    """The output socket feeding input ``socket``, through reroutes; None if unlinked.

    Raises _Unsupported for muted or invalid links (what Cycles does with them is not read here).
    """
    try:
        return source_socket(socket, strict=True)
    except MutedLink as error:
        raise _Unsupported(str(error)) from None


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
        image = _original(node.image)
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


def _image_source(world, output, scene):
    """The ``ImageSource`` of the evaluated ``world``, or _Unsupported saying why it needs a
    capture."""
    if output.inputs["Volume"].is_linked:
        raise _Unsupported("the world has a volume shader")
    source = _source_socket(output.inputs["Surface"])
    background = source.node
    if background.type != "BACKGROUND" or background.mute:
        raise _Unsupported(f"the world's surface is a {background.bl_label} node")
    strength = background.inputs["Strength"]
    if strength.is_linked:
        raise _Unsupported("the Background's Strength is linked")
    try:  # what the world is without a World Edit (``world_edit``) in its colour
        colour = colour_source(background.inputs["Color"], strict=True)
    except MutedLink as error:
        raise _Unsupported(str(error)) from None
    if colour is None:
        raise _Unsupported("the Background has a plain colour")
    texture = colour.node
    if texture.type != "TEX_ENVIRONMENT" or texture.mute or colour.name != "Color":
        raise _Unsupported(f"the Background's Color comes from {texture.bl_label} {colour.name}")
    if texture.projection not in PROJECTIONS:
        raise _Unsupported(f"the Environment Texture's projection is {texture.projection}")
    image = _original(texture.image)
    if image.source not in STILL_SOURCES:
        raise _Unsupported(f"image '{image.name}' is a {image.source.lower()}")
    reason = undecodable_reason(image)
    if reason:
        raise _Unsupported(reason)
    pixels = None
    if not image.is_float and image.depth == 32 and image.alpha_mode in ("STRAIGHT", "PREMUL"):
        try:  # 8-bit with an alpha channel: only its texels tell whether it is exact
            pixels = linear_pixels(image)
        except DecodeError as why:
            raise _Unsupported(str(why)) from None
    return ImageSource(
        world=world.name,
        image=image,
        projection=texture.projection,
        rotation=_vector_rotation(texture),
        strength=float(strength.default_value),
        colour_space=image.colorspace_settings.name,
        working_space=compat.working_space(),
        frame=scene.frame_current,
        _pixels=pixels,
    )


# -- the reader --------------------------------------------------------------------------------


def _original(datablock):
    return getattr(datablock, "original", None) or datablock


def _tag_driver_targets(world):
    """Tag the IDs that drivers of ``world`` and its node tree read, so that the next
    evaluation runs those drivers again (a custom property set from Python,
    ``scene["k"] = 3``, tags nothing, and after a render the depsgraph kept the driven
    Strength of the old value, while the next render, with a depsgraph of its own, shows the
    new one). A tag changes no data."""
    for owner in (world, world.node_tree):
        animation = getattr(owner, "animation_data", None) if owner is not None else None
        if animation is None:
            continue
        for curve in animation.drivers:
            for variable in curve.driver.variables:
                for target in variable.targets:
                    if target.id is not None:
                        target.id.update_tag()


def _evaluated_world(scene, depsgraph):
    """``scene.world`` as the depsgraph evaluates it at the scene's current frame (drivers
    run again when no ``depsgraph`` is given: what the next render shows)."""
    if depsgraph is None:
        _tag_driver_targets(scene.world)
        context = bpy.context
        if context.scene == scene and context.view_layer is not None:
            depsgraph = context.evaluated_depsgraph_get()
        else:
            with context.temp_override(scene=scene, view_layer=scene.view_layers[0]):
                depsgraph = context.evaluated_depsgraph_get()
    return scene.world.evaluated_get(depsgraph)


def read_world(scene, depsgraph=None):
    """What ``scene``'s world is: an ``ImageSource`` or a ``ProceduralSource``.

    The node tree is read as ``depsgraph`` (default: the scene's evaluated depsgraph)
    evaluates it, so keyed and driven Strength and Mapping rotation are those of the scene's
    current frame, as the next render shows them. No pixels are read, except the alpha of an
    8-bit image with an alpha channel (transparent texels need a capture). Raises WorldError
    (a ValueError) for a world that cannot give any lighting: no world, no node tree, no
    active World Output or nothing connected to it, an image texture without its image or
    an image without pixel data. Changes nothing.
    """
    world = scene.world if scene is not None else None
    _check_world(world, scene.name if scene is not None else "(none)")
    evaluated = _evaluated_world(scene, depsgraph)
    output = _check_world(evaluated, scene.name)
    _check_images(world, output)
    try:
        return _image_source(world, output, scene)
    except _Unsupported as why:
        return ProceduralSource(world=world.name, reason=str(why))


# -- the coefficients --------------------------------------------------------------------------


def _project_image(source, pixels):
    """The L_lm of the image itself (before the Mapping rotation and Strength)."""
    project = project_equirect if source.projection == "EQUIRECTANGULAR" else project_mirror_ball
    try:
        return project(pixels)
    except ValueError as error:
        raise WorldError(
            f"image '{source.image.name}' of world '{source.world}': {error}"
        ) from None


def _error(pixels, coeffs, count):
    """(mean, max) of ``irradiance.error_estimate`` of equirect ``pixels`` and their own
    ``coeffs`` at ``count`` normals, or None (count 0, a channel without light)."""
    if not count:
        return None
    estimate = error_estimate(pixels, coeffs, count)
    return None if estimate is None else (estimate["mean"], estimate["max"])


def world_coefficients(scene, capture_width=256, depsgraph=None, error_normals=0,
                       nonfinite="raise", keep_radiance=False):
    """(9, 3) float64 L_lm of ``scene``'s world as Cycles renders it, and a ``WorldInfo``.

    ``read_world`` decides: an image is projected (``core``), anything else is captured by
    Cycles at ``capture_width`` × ``capture_width``/2 at the scene's current frame.
    ``error_normals`` > 0 also measures the 9-term error against the world's brute-force
    irradiance at that many normals (``WorldInfo.error``, ``irradiance.error_estimate``; not
    for mirror-ball images), which costs that many passes over a map at most about 512 wide.
    ``nonfinite`` "zero": NaN/Inf texels of a world image count as black. ``keep_radiance``:
    the ``WorldInfo`` also holds the map read (``world_radiance``'s result; None for a mirror
    ball), so that what needs the radiance too reads the world once. Raises WorldError (a ValueError) when the world
    cannot give any lighting.
    """
    if nonfinite not in ("raise", "zero"):
        raise ValueError(f'nonfinite must be "raise" or "zero", got {nonfinite!r}')
    start = time.perf_counter()
    source = read_world(scene, depsgraph)
    world = scene.world
    if isinstance(source, ImageSource):
        pixels = source.pixels()
        if nonfinite == "zero":  # NaN/Inf texels black, in the projection and the estimate
            pixels = zero_nonfinite(pixels)
        own = _project_image(source, pixels)
        # The Mapping node turns the lookup direction by R: the lighting is the image turned by
        # Rᵀ, and Strength scales it. Neither changes the error as a fraction of the light, so
        # it is measured on the image itself (the same normals, turned with it).
        coeffs = apply_mapping(own, source.strength, source.rotation)
        error = None
        if source.projection == "EQUIRECTANGULAR":
            error = _error(pixels, own, error_normals)
        info = WorldInfo(
            source="image",
            world=world.name,
            elapsed=time.perf_counter() - start,
            working_space=source.working_space,
            image=source.image.name,
            projection=source.projection,
            rotation=source.rotation,
            strength=source.strength,
            error=error,
            error_normals=error_normals if error is not None else 0,
            radiance=((zero_nonfinite(pixels), source.strength, source.rotation)
                      if keep_radiance and source.projection == "EQUIRECTANGULAR" else None),
        )
        return coeffs, info
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
    error = _error(pixels, coeffs, error_normals)
    info = WorldInfo(
        source="capture",
        world=world.name,
        elapsed=time.perf_counter() - start,
        working_space=compat.working_space(),
        reason=source.reason,
        capture_width=int(capture_width),
        error=error,
        error_normals=error_normals if error is not None else 0,
        radiance=(zero_nonfinite(pixels), 1.0, None) if keep_radiance else None,
    )
    return coeffs, info


def world_radiance(scene, capture_width=256):
    """``scene``'s world as an equirect map, for what needs its radiance rather than its nine
    terms (``shading.glossy``): (pixels (H, W, 3 or 4) float32 rows top to bottom, Strength,
    Mapping XYZ Euler or None). An equirect image is read as Compute reads it (NaN/Inf texels
    black); any other world is captured by Cycles at ``capture_width`` (then Strength 1, no
    rotation: the capture is the world as it shows). WorldError when it cannot be read."""
    source = read_world(scene)
    if isinstance(source, ImageSource) and source.projection == "EQUIRECTANGULAR":
        return zero_nonfinite(source.pixels()), source.strength, source.rotation
    try:
        pixels = capture_world(scene.world, capture_width, frame=scene.frame_current)
    except CaptureError as error:
        raise WorldError(f"world '{scene.world.name}' could not be captured: {error}") from None
    return zero_nonfinite(pixels), 1.0, None
