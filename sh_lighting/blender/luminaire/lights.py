"""The lights a measured luminaire is made of (``build``): its Cycles IES node, the fitted
EEVEE lamps for every near-field cell, the near field's Cycles lights, all children of the
luminaire, their power, colour and temperature driven by its own (simple-expression drivers,
no scripts).

Engine switches (docs/blender.md): a light EEVEE should ignore has its ``FACTORS`` at 0 (Cycles
ignores them); one Cycles should ignore has its node tree's Emission Strength at 0 (EEVEE
ignores it). A fitted lamp of on-axis intensity c cd has power ``CANDELA_TO_WATT`` × c × the
luminaire's power / the number of cells.
"""

import math

import bpy
from mathutils import Matrix, Vector

LUMENS_PER_WATT = 177.83  # Blender's IES node: D65's luminous efficacy
CANDELA_TO_WATT = 4.0 * math.pi / LUMENS_PER_WATT  # Blender's IES node: Strength per candela
FACTORS = ("diffuse_factor", "specular_factor", "volume_factor", "transmission_factor")


def ies_nodes(data, text):
    if data.node_tree is None:
        data.use_nodes = True
    tree = data.node_tree
    emission = next(n for n in tree.nodes if n.type == "EMISSION")
    ies = tree.nodes.new("ShaderNodeTexIES")
    ies.mode = "INTERNAL"
    ies.ies = text
    ies.location = (emission.location.x - 250, emission.location.y)
    tree.links.new(ies.outputs["Fac"], emission.inputs["Strength"])


def root_emits(data, emits):
    """Link (far field) or cut (near field: the cells emit) the luminaire's IES node."""
    tree = data.node_tree
    emission = next(n for n in tree.nodes if n.type == "EMISSION")
    strength = emission.inputs["Strength"]
    for link in list(strength.links):
        tree.links.remove(link)
    if emits:
        ies = next(n for n in tree.nodes if n.type == "TEX_IES")
        tree.links.new(ies.outputs["Fac"], strength)
    else:
        strength.default_value = 0.0


def make_all(root, collection, lamps, cells, text, far_radius):
    """The EEVEE lamps for every cell, and the near field's Cycles lights (none when far)."""
    root_emits(root.data, not cells.near)
    if not cells.near:
        return _make_lamps(root, collection, lamps, far_radius, cells), []
    return (_make_lamps(root, collection, lamps, cells.half_size, cells),
            _make_cycles_cells(root, collection, text, cells))


def _make_cycles_cells(root, collection, text, cells):
    made = []
    for index, centre in enumerate(cells.centres):
        name = f"{root.name} Cycles cell {index + 1}"
        data = bpy.data.lights.new(name, type="POINT")
        data.shadow_soft_size = cells.half_size
        for factor in FACTORS:  # EEVEE: the fitted lamps render
            if hasattr(data, factor):
                setattr(data, factor, 0.0)
        ies_nodes(data, text)
        _drive_power_and_colour(data, root, 1.0 / cells.count)
        made.append(_child(root, collection, name, data, centre))
    return made


def _child(root, collection, name, data, location):
    obj = bpy.data.objects.new(name, data)
    obj.parent = root
    obj.location = tuple(float(v) for v in location)
    obj.hide_select = True
    collection.objects.link(obj)
    return obj


def _drive_power_and_colour(data, root, watts_per_watt):
    _drive(data, "energy", root, "data.energy", f"var * {watts_per_watt!r}")
    for channel in range(3):
        _drive(data, "color", root, f"data.color[{channel}]", "var", channel)
    if hasattr(data, "temperature"):  # Blender 5.0's Light Temperature
        _drive(data, "use_temperature", root, "data.use_temperature", "var")
        _drive(data, "temperature", root, "data.temperature", "var")


def _make_lamps(root, collection, lamps, radius, cells):
    made = []
    for cell, centre in enumerate(cells.centres):
        for index, lamp in enumerate(lamps):
            suffix = f" cell {cell + 1}" if cells.near else ""
            made.append(_make_lamp(root, collection, lamp, radius, f"{index + 1}{suffix}",
                                   centre, cells.count))
    return made


def _make_lamp(root, collection, lamp, radius, label, centre, count):
    """One fitted lamp at ``centre`` (the luminaire's axes) with 1 / ``count`` of its power."""
    name = f"{root.name} EEVEE {label}"
    data = bpy.data.lights.new(name, type=lamp.kind)
    data.shadow_soft_size = radius
    if lamp.kind == "SPOT":
        data.spot_size = min(2.0 * lamp.half_angle, math.pi)
        data.spot_blend = lamp.blend
        data.show_cone = False
    if data.node_tree is None:
        data.use_nodes = True
    emission = next(n for n in data.node_tree.nodes if n.type == "EMISSION")
    emission.inputs["Strength"].default_value = 0.0  # Cycles: the IES light renders
    _drive_power_and_colour(data, root, lamp.candela * CANDELA_TO_WATT / count)
    obj = _child(root, collection, name, data, centre)
    obj.rotation_mode = "QUATERNION"
    z = -Vector(lamp.axis)
    x = Vector(lamp.x_axis) if lamp.x_axis is not None else z.orthogonal().normalized()
    obj.rotation_quaternion = Matrix((x, z.cross(x), z)).transposed().to_quaternion()
    obj.scale = (lamp.scale[0], lamp.scale[1], 1.0)
    return obj


def _drive(data, prop, root, path, expression, index=-1):
    curve = data.driver_add(prop, index)
    driver = curve.driver
    driver.type = "SCRIPTED"
    var = driver.variables.new()
    var.name = "var"
    var.type = "SINGLE_PROP"
    var.targets[0].id_type = "OBJECT"
    var.targets[0].id = root
    var.targets[0].data_path = path
    driver.expression = expression


def delete_lights(lamps):
    for lamp in list(lamps):
        if lamp is None:
            continue
        data = lamp.data
        bpy.data.objects.remove(lamp)
        if data is not None and data.users == 0:
            bpy.data.lights.remove(data)
