"""EEVEE's glossy reflections of the world under Keep BSDF, given back by prefiltered maps.

Keep BSDF hides the world from EEVEE's lighting, reflections included. ``write_maps`` stores
the world prefiltered with GGX at ``core.glossy.ROUGHNESS_LEVELS`` as packed float images
(``IMAGE_MARKER``), the add-on's by identity: each image's record names the image itself and
the world's record lists its maps by name, so a user's copy is never rewritten or deleted.
``add_eevee_reflections`` gives each Principled BSDF an EEVEE-only emission
coverage · P(r_eff, N + t (R − N)) · (F0 · A(r, n·v) + B(r, n·v)) (the split sum of
``core.glossy``, with multiple scattering), F0 = (1 − Metallic) F0_IOR + Metallic · Base Color,
t and r_eff read from a 16 × 16 table image. Other reflecting shaders, Coat and Sheen are not
modelled (``unmodelled``). Details: docs/modules.md.
"""

import json

import bpy
import numpy as np

from ...core.glossy import ROUGHNESS_LEVELS, environment_brdf_table, level_maps
from ..data import compat
from ..data.node_links import source_socket
from ..world.reader import WorldError, read_world, world_radiance
from .keep_bsdf import PRINCIPLED, coverage_factors, dielectric_f0, product

# Custom property of the images made here: JSON {"world": world name, "roughness": level,
# "image": the image's own name} (an older version's has no "image": its name was the one
# ``_made_name`` gives).
IMAGE_MARKER = "sh_lighting_glossy"
# Custom property of a world with maps: JSON {"world": its name, "maps": [image names]}.
WORLD_MARKER = "sh_lighting_glossy_maps"
LABEL = "SH glossy"
# Shaders with reflections the maps do not give back in EEVEE (4.2-5.0 names).
UNMODELLED_SHADERS = frozenset({
    "ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic", "ShaderNodeBsdfMetallic",
    "ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction", "ShaderNodeBsdfSheen",
    "ShaderNodeBsdfToon",
})
# Principled layers whose reflections are not modelled, when their weight is not 0.
UNMODELLED_LAYERS = ("Coat Weight", "Sheen Weight")
# The split-sum table image's marker: version 2 holds t and r_eff too, twice as wide
# (``table_image``; version 1, no "version": A and B only).
TABLE_RECORD = {"table": "split sum", "version": 2}


def _record(image):
    try:
        record = json.loads(image[IMAGE_MARKER])
    except (KeyError, ValueError, TypeError):
        return None
    return record if isinstance(record, dict) else None


def _made_name(record):
    """The name an image of ``record`` was given when it was made (older records)."""
    if "table" in record:
        return f"{LABEL} split sum"
    try:
        return f"{LABEL} {record['world']} r{float(record['roughness']):.2f}"
    except (KeyError, TypeError, ValueError):
        return None


def is_made(image):
    """Whether ``image`` is one the add-on made (a map or the split-sum table), by identity:
    its record names the image itself, which a copy (another name) does not."""
    if image.library is not None or IMAGE_MARKER not in image:
        return False
    record = _record(image)
    return record is not None and record.get("image", _made_name(record)) == image.name


def _world_record(world):
    try:
        record = json.loads(world[WORLD_MARKER])
    except (KeyError, ValueError, TypeError):
        return None
    return record if isinstance(record, dict) and isinstance(record.get("maps"), list) else None


def _owns(world, record):
    """Whether the maps of ``world``'s ``record`` are its own: it is the world the record
    names, or no other world holds the same record (a rename). Another world with the same
    record makes this one its copy (a copy inherits custom properties)."""
    if record.get("world") == world.name:
        return True
    text = world[WORLD_MARKER]
    return not any(other != world and other.get(WORLD_MARKER) == text
                   for other in bpy.data.worlds)


def maps_of(world):
    """The images ``write_maps`` made for ``world``, one per roughness level in order, or
    None when there is not a full set."""
    if world is None:
        return None
    record = _world_record(world)
    if record is not None:
        if not _owns(world, record):
            return None
        images = [bpy.data.images.get(name) for name in record["maps"]]
        if len(images) == len(ROUGHNESS_LEVELS) and all(
                image is not None and is_made(image)
                and _record(image).get("roughness") == r
                for image, r in zip(images, ROUGHNESS_LEVELS)):
            return images
        return None
    found = {}  # a file from before the world's record: by the images' world name
    for image in bpy.data.images:
        if is_made(image) and _record(image).get("world") == world.name:
            found[_record(image).get("roughness")] = image
    if any(r not in found for r in ROUGHNESS_LEVELS):
        return None
    return [found[r] for r in ROUGHNESS_LEVELS]


def write_maps(scene, radiance=None):
    """Prefilter ``scene``'s world (``core.glossy.level_maps``) into its images, made or
    rewritten in place; returns them. ``radiance``: the world already read (``world_radiance``'s
    result), else it is read here. WorldError (nothing written) when it cannot be read."""
    world = scene.world
    if world is None:
        raise WorldError(f"scene '{scene.name}' has no world to reflect")
    pixels, strength, euler = radiance or world_radiance(scene)
    levels = level_maps(pixels, strength, euler)
    images = maps_of(world) or [None] * len(ROUGHNESS_LEVELS)
    written = []
    for r, level, image in zip(ROUGHNESS_LEVELS, levels, images):
        height, width = level.shape[:2]
        if image is None:
            image = bpy.data.images.new(f"{LABEL} {world.name} r{r:.2f}", width, height,
                                        alpha=False, float_buffer=True)
        elif tuple(image.size) != (width, height):
            image.scale(width, height)
        image.colorspace_settings.name = compat.working_space()  # that of the pixels
        # EEVEE uploads float images as half floats by default: 65504 at most, a sun's
        # texel in the r = 0 map can be brighter (sunrise.exr's: 8.6e3)
        image.use_half_precision = False
        rgba = np.ones((height, width, 4), dtype=np.float32)
        rgba[..., :3] = level[::-1]  # Image.pixels are bottom row first
        image.pixels.foreach_set(rgba.ravel())
        image.pack()
        image[IMAGE_MARKER] = json.dumps({"world": world.name, "roughness": r,
                                          "image": image.name})
        written.append(image)
    world[WORLD_MARKER] = json.dumps({"world": world.name,
                                      "maps": [image.name for image in written]})
    return written


def follow_world(scene, radiance=None):
    """Rewrite the maps of ``scene``'s world if it has them (Compute from World, which passes
    the ``radiance`` it read: ``write_maps``); True if so."""
    if maps_of(scene.world) is None:
        return False
    write_maps(scene, radiance)
    return True


def remove_maps():
    """Delete every image made here (Remove, once no material uses them): the maps and the
    table, by identity (``is_made``: a user's copy stays), and the worlds' records of them."""
    for image in [i for i in bpy.data.images if is_made(i)]:
        bpy.data.images.remove(image)
    for world in bpy.data.worlds:
        if world.library is None and WORLD_MARKER in world:
            del world[WORLD_MARKER]


def unmodelled(leaves):
    """Names of the shaders and layers among ``leaves`` (``diffuse_weight.surface_leaves``)
    whose reflections the maps do not give back."""
    names = []
    for leaf in leaves:
        node = leaf.node
        if node.bl_idname in UNMODELLED_SHADERS:
            names.append(f"{node.bl_label} '{node.name}'")
        elif node.bl_idname == PRINCIPLED:
            for layer in UNMODELLED_LAYERS:
                socket = node.inputs.get(layer)
                if socket is not None and (socket.is_linked or socket.default_value > 0.0):
                    names.append(f"{layer.split()[0]} of '{node.name}'")
    return names


def _vector(b, operation, *operands):
    """A Vector Math node of ``operands`` (output sockets or numbers, a number filling a
    vector); for "SCALE" the second is the scale. Returns its output socket."""
    node = b.node("ShaderNodeVectorMath", f"{LABEL} ({operation.lower()})", operation=operation)
    sockets = list(node.inputs)
    if operation == "SCALE":
        sockets = [node.inputs[0], node.inputs["Scale"]]
    for socket, value in zip(sockets, operands):
        if not isinstance(value, (int, float)):
            b.tree.links.new(value, socket)
        elif socket.type == "VECTOR":
            socket.default_value = (value, value, value)
        else:
            socket.default_value = value
    return node.outputs["Value" if operation == "DOT_PRODUCT" else "Vector"]


def _lookup(b, images, reflected, roughness):
    """The maps at ``reflected``, linearly interpolated between the levels by ``roughness``."""
    result = None
    for index, (r, image) in enumerate(zip(ROUGHNESS_LEVELS, images)):
        texture = b.node("ShaderNodeTexEnvironment", f"{LABEL} r = {r:.2f}", image=image,
                         interpolation="Linear", projection="EQUIRECTANGULAR")
        b.tree.links.new(reflected, texture.inputs["Vector"])
        if result is None:
            result = texture.outputs["Color"]
            continue
        previous = ROUGHNESS_LEVELS[index - 1]
        step = r - previous
        fac = b.math("MULTIPLY_ADD", roughness, 1.0 / step, -previous / step, label=LABEL,
                     clamp=True)
        mix = b.node("ShaderNodeMix", f"{LABEL} (between levels)", data_type="RGBA")
        b.tree.links.new(fac, mix.inputs["Factor"])
        b.tree.links.new(result, mix.inputs[6])  # A (colour)
        b.tree.links.new(texture.outputs["Color"], mix.inputs[7])  # B (colour)
        result = mix.outputs[2]  # Result (colour)
    return result


def _table(b, table, roughness, n_dot_v):
    """The split sum's table (``table_image``) looked up at (n·v, r): sockets (A, B, t,
    r_eff), interpolated bilinearly between its texel centres. Through Environment Texture
    nodes at the directions whose equirectangular (u, v) are (n·v / 2, r) for (A, B, t) and
    (½ + n·v / 2, r) for r_eff (``core.equirect.uv_to_direction``: φ = π − 2π u,
    θ = π (1 − v)), n·v and r clamped to the outer texel centres (no blend across the
    image's edges and halves): EEVEE reads an Image Texture node of Linear interpolation
    through mipmaps picked by the screen derivatives of (n·v, r), which over a small
    sphere's few pixels average the table over a quarter of its width and more; its
    Environment Texture takes no mipmaps (benchmarks/bench_real_scene, sunrise.exr's glossy
    sphere, EEVEE: 36.3 % through an Image Texture, 35.2 % at the nearest texel of a 64 × 64
    table, 34.7 % so; the same nodes in Cycles 34.5 %, 35.0 %, 34.5 %)."""
    size = table.size[1]
    low, high = 0.5 / size, 1.0 - 0.5 / size
    u = b.math("MINIMUM", b.math("MAXIMUM", n_dot_v, low, label=LABEL), high, label=LABEL)
    v = b.math("MINIMUM", b.math("MAXIMUM", roughness, low, label=LABEL), high, label=LABEL)
    theta = b.math("MULTIPLY_ADD", v, -np.pi, np.pi, label=LABEL)
    sin_theta = b.math("SINE", theta, label=LABEL)
    cos_theta = b.math("COSINE", theta, label=LABEL)
    colours = []
    for half in (0.0, 0.5):
        phi = b.math("MULTIPLY_ADD", u, -np.pi, np.pi - 2.0 * np.pi * half, label=LABEL)
        where = b.node("ShaderNodeCombineXYZ", f"{LABEL} (n·v, roughness) as a direction")
        b.tree.links.new(b.math("MULTIPLY", sin_theta, b.math("COSINE", phi, label=LABEL),
                                label=LABEL), where.inputs["X"])
        b.tree.links.new(b.math("MULTIPLY", sin_theta, b.math("SINE", phi, label=LABEL),
                                label=LABEL), where.inputs["Y"])
        b.tree.links.new(cos_theta, where.inputs["Z"])
        lookup = b.node("ShaderNodeTexEnvironment",
                        f"{LABEL}: split sum {'(A, B, t)' if half == 0.0 else 'r_eff'}",
                        image=table, interpolation="Linear", projection="EQUIRECTANGULAR")
        b.tree.links.new(where.outputs[0], lookup.inputs["Vector"])
        colours.append(lookup.outputs["Color"])
    parts = b.node("ShaderNodeSeparateXYZ", f"{LABEL} (A, B, t)")
    b.tree.links.new(colours[0], parts.inputs[0])
    effective = b.node("ShaderNodeSeparateXYZ", f"{LABEL} (r_eff)")
    b.tree.links.new(colours[1], effective.inputs[0])
    return (*parts.outputs, effective.outputs["X"])


def _specular(b, scale, bias, f0):
    """The colour socket of the split sum's reflectance with the multiple-scattering term
    (``core.glossy``) from the table's ``scale`` A and ``bias`` B:
    F0 A + B + (F0 A + B) F_avg (1 − E) / (1 − F_avg (1 − E))."""
    single = _vector(b, "MULTIPLY_ADD", f0, scale, bias)  # F0 A + B
    missing = b.math("SUBTRACT", 1.0, b.math("ADD", scale, bias, label=LABEL), label=LABEL)
    average = _vector(b, "MULTIPLY_ADD", f0, 20.0 / 21.0, 1.0 / 21.0)  # F0 + (1 − F0)/21
    lost = _vector(b, "SCALE", average, missing)
    gain = _vector(b, "DIVIDE", _vector(b, "MULTIPLY", single, lost),
                   _vector(b, "SUBTRACT", 1.0, lost))
    return _vector(b, "ADD", single, gain)


def _dominant(b, reflected, normal, factor):
    """The lookup direction N + t (R − N), t = ``factor`` read from the table
    (``core.glossy.lobe_factor``: toward the GGX lobe's mean direction)."""
    lean = _vector(b, "SCALE", _vector(b, "SUBTRACT", reflected, normal), factor)
    return _vector(b, "ADD", normal, lean)


def _leaf_reflection(b, leaf, images, table, geometry):
    """The colour socket of one Principled leaf's glossy reflection (module docstring)."""
    bsdf = leaf.node
    normal = source_socket(bsdf.inputs["Normal"]) or geometry.outputs["Normal"]
    incoming = geometry.outputs["Incoming"]
    # Vector Math Reflect gives I − 2 (I·N) N = −R
    reflected = _vector(b, "SCALE", _vector(b, "REFLECT", incoming, normal), -1.0)
    roughness = b.math("MAXIMUM", ("follow", bsdf.inputs["Roughness"]), 0.0, label=LABEL,
                       clamp=True)
    n_dot_v = b.math("MAXIMUM", _vector(b, "DOT_PRODUCT", normal, incoming), 1e-4, label=LABEL,
                     clamp=True)
    scale, bias, factor, effective = _table(b, table, roughness, n_dot_v)
    reflected = _dominant(b, reflected, normal, factor)
    metallic = bsdf.inputs["Metallic"]
    f0 = dielectric_f0(b, bsdf, label=LABEL)
    base = b.node("ShaderNodeVectorMath", f"{LABEL} (metal F0)", operation="SCALE")
    b.follow(base.inputs[0], bsdf.inputs["Base Color"])
    b.follow(base.inputs["Scale"], metallic)
    dielectric = b.math("MULTIPLY", f0 if f0 is not None else 0.04,
                        b.math("SUBTRACT", 1.0, ("follow", metallic), label=LABEL), label=LABEL)
    specular = _specular(b, scale, bias, _vector(b, "ADD", base.outputs["Vector"], dielectric))
    weight = product(b, coverage_factors(b, leaf), label=LABEL)
    if not isinstance(weight, float):
        specular = _vector(b, "MULTIPLY", specular, weight)
    return _vector(b, "MULTIPLY", _lookup(b, images, reflected, effective), specular)


def maps_for(scene):
    """(the maps of ``scene``'s world, written first if it has none, the split sum's table
    image); None when the world cannot be read (``reflection_problem`` says why)."""
    if not shows_reflections(scene.world):
        return None
    images = maps_of(scene.world)
    try:
        images = images or write_maps(scene)
    except WorldError:
        return None
    return images, table_image()


def table_image():
    """The file's image of ``core.glossy.environment_brdf_table``: (A, B, t) in the left
    half, r_eff in the right half's red (``_table``), made and packed when missing. One of
    an older table (A and B only, read by the nodes of an older Apply) is left to those
    nodes; Remove deletes both."""
    for image in bpy.data.images:
        record = _record(image) if is_made(image) else None
        if record is not None and {k: v for k, v in record.items() if k != "image"} == (
                TABLE_RECORD):
            return image
    table = environment_brdf_table()
    size = table.shape[0]
    image = bpy.data.images.new(f"{LABEL} split sum", 2 * size, size, alpha=False,
                                float_buffer=True)
    image.colorspace_settings.name = "Non-Color"
    image.use_half_precision = False
    image[IMAGE_MARKER] = json.dumps({**TABLE_RECORD, "image": image.name})
    rgba = np.ones((size, 2 * size, 4), dtype=np.float32)
    rgba[:, :size, :3] = table[..., :3]
    rgba[:, size:, :3] = table[..., 3:]
    # row 0 (r near 0) is Image.pixels' first, bottom row: v = r
    image.pixels.foreach_set(rgba.ravel())
    image.pack()
    return image


def shows_reflections(world):
    """Whether ``world`` is seen by glossy rays (World > Ray Visibility > Glossy): when it is
    not, Cycles shows no reflections of it, and neither do the maps in EEVEE."""
    return world is None or world.cycles_visibility.glossy


def reflection_problem(scene):
    """Why ``scene``'s world has no maps to reflect, or None when it has them (or there is no
    world: nothing to reflect, in EEVEE's own lighting either)."""
    if not shows_reflections(scene.world):
        return (f"World '{scene.world.name}' has Glossy ray visibility off (Cycles shows no "
                "reflections of it either)")
    if scene.world is None or maps_of(scene.world) is not None:
        return None
    try:
        read_world(scene)
    except WorldError as error:
        return str(error)
    return "no Principled BSDF asked for them"


def add_eevee_reflections(b, leaves, outputs, active, maps):
    """Add the world's reflections off the Principled BSDFs among ``leaves`` (the surface's,
    ``diffuse_weight.surface_leaves``) to what EEVEE renders (module docstring): to each
    Material Output of ``outputs`` whose target is EEVEE, else to a new one (appended to
    ``b.added``) with the links of ``active``. ``maps``: returns the images or None (then,
    like without a Principled BSDF, nothing is added). True when added."""
    principled = [leaf for leaf in leaves if leaf.node.bl_idname == PRINCIPLED]
    found = maps() if principled else None
    if found is None:
        return False
    images, table = found
    geometry = b.node("ShaderNodeNewGeometry", LABEL)
    total = None
    for leaf in principled:
        colour = _leaf_reflection(b, leaf, images, table, geometry)
        total = colour if total is None else _vector(b, "ADD", total, colour)
    emission = b.node("ShaderNodeEmission", f"{LABEL}: the world's reflections (EEVEE)")
    b.tree.links.new(total, emission.inputs["Color"])
    emission.inputs["Strength"].default_value = 1.0
    add_for_eevee(b, emission.outputs[0], outputs, active, "BSDF + SH diffuse + SH glossy (EEVEE)")
    return True


def add_for_eevee(b, shader, outputs, active, label):
    """Add ``shader`` to what EEVEE renders and Cycles does not: to each Material Output of
    ``outputs`` whose target is EEVEE (an Add Shader labelled ``label``), else to a new one
    (appended to ``b.added``) with the links of ``active``, which stays Cycles' output."""
    targets = [output for output in outputs if output.target == "EEVEE"]
    if not targets:
        output = b.node("ShaderNodeOutputMaterial", "SH Lighting: EEVEE Material Output",
                        target="EEVEE")
        for socket in active.inputs:
            for link in socket.links:
                copy = b.tree.links.new(link.from_socket, output.inputs[socket.identifier])
                copy.is_muted = link.is_muted
        active.is_active_output = True
        targets = [output]
    for output in targets:
        surface = output.inputs["Surface"]
        original = source_socket(surface)
        if original is None:
            b.tree.links.new(shader, surface)
            continue
        add = b.node("ShaderNodeAddShader", label)
        b.tree.links.new(original, add.inputs[0])
        b.tree.links.new(shader, add.inputs[1])
        b.tree.links.new(add.outputs[0], surface)
