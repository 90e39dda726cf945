"""The gains s_lm as the render reads them: three 3-float properties, copied by drivers.

The node groups read the lighting through View Layer Attribute nodes, and EEVEE's shader
compile grows steeply with their number on software OpenGL: 12 compile in 7 s, 18 (nine
coefficients and nine gains) in 175 s (benchmarks/REPORT.md, "compile"). So the groups read
the nine gains as three vectors, ``scene["sh_gains_0"]`` = (s00, s1-1, s10), ``["sh_gains_1"]``
= (s11, s2-2, s2-1), ``["sh_gains_2"]`` = (s20, s21, s22): 12 lookups in all. Each element is
a driver (type Sum, no Python: farm-safe) on the gain ``scene["sh_L.._gain"]``, which stays
the one property users edit and keyframe; Blender evaluates it after the keyframes at every
frame and remaps it to the copy when a scene is copied. The copy is exact (float32, as
every attribute the render reads).
"""

PACK_NAMES = ("sh_gains_0", "sh_gains_1", "sh_gains_2")
PACK_SIZE = 3
DESCRIPTION = (
    "The gains {names} as the SH node groups read them (a driver copies each gain here at "
    "every frame): edit or keyframe the gains themselves, not this"
)


def pack_of(index):
    """(pack property name, element) holding gain ``index`` (0..8)."""
    return PACK_NAMES[index // PACK_SIZE], index % PACK_SIZE


def _path(name):
    return f'["{name}"]'


def _is_pack(value):
    """True for an ID property array of 3 floats (an int array would truncate the gains)."""
    return (hasattr(value, "to_list") and getattr(value, "typecode", "") in ("f", "d")
            and len(value) == PACK_SIZE)


def _driver_is_right(curve, scene, gain_name):
    driver = curve.driver
    if (driver.type != "SUM" or len(driver.variables) != 1 or len(curve.keyframe_points)
            or len(curve.modifiers)):
        return False
    variable = driver.variables[0]
    target = variable.targets[0]
    return (variable.type == "SINGLE_PROP" and target.id_type == "SCENE"
            and target.id == scene and target.data_path == _path(gain_name))


def ensure(scene, gain_names):
    """Give ``scene`` the three packs, each element driven by its gain in ``gain_names``
    (nine names), writing only what is missing or wrong; the names of the packs written.
    A scene linked from a library is left as it is (its file keeps its own)."""
    if scene.library is not None:
        return []
    written = []
    for pack, name in enumerate(PACK_NAMES):
        gains = gain_names[pack * PACK_SIZE:(pack + 1) * PACK_SIZE]
        if not _is_pack(scene.get(name)):
            scene[name] = [float(scene.get(g, 1.0)) for g in gains]
            written.append(name)
        scene.id_properties_ui(name).update(
            description=DESCRIPTION.format(names=", ".join(gains)), subtype="NONE")
        animation = scene.animation_data or scene.animation_data_create()
        for element, gain_name in enumerate(gains):
            curve = animation.drivers.find(_path(name), index=element)
            if curve is not None and _driver_is_right(curve, scene, gain_name):
                continue
            if curve is not None:
                animation.drivers.remove(curve)
            curve = scene.driver_add(_path(name), element)
            # driver_add maps the driver through keys (0, 0), (1, 1) (5.0; they round 1
            # ulp) or a Generator modifier (4.2): without them the F-curve passes the
            # driver's value on as it is.
            for point in reversed(list(curve.keyframe_points)):
                curve.keyframe_points.remove(point)
            for modifier in reversed(list(curve.modifiers)):
                curve.modifiers.remove(modifier)
            curve.driver.type = "SUM"
            variable = curve.driver.variables.new()
            variable.name = "gain"
            variable.type = "SINGLE_PROP"
            variable.targets[0].id_type = "SCENE"
            variable.targets[0].id = scene
            variable.targets[0].data_path = _path(gain_name)
            if name not in written:
                written.append(name)
    return written


def broken(scene, gain_names):
    """[(pack name, message)] of the packs that are missing, not 3 numbers or not driven by
    their gains, once ``scene`` has any pack or pack driver (a file from before the packs,
    whose groups read the gains directly, has none: nothing is wrong with it)."""
    animation = scene.animation_data
    drivers = {} if animation is None else {
        (c.data_path, c.array_index): c for c in animation.drivers}
    if not any(name in scene for name in PACK_NAMES) and not any(
            path == _path(name) for path, _i in drivers for name in PACK_NAMES):
        return []
    found = []
    for pack, name in enumerate(PACK_NAMES):
        gains = gain_names[pack * PACK_SIZE:(pack + 1) * PACK_SIZE]
        value = scene.get(name)
        if value is None:
            why = "is missing"
        elif not _is_pack(value):
            why = "is not 3 decimal numbers"
        elif not all(drivers.get((_path(name), e)) is not None
                     and _driver_is_right(drivers[(_path(name), e)], scene, g)
                     for e, g in enumerate(gains)):
            why = "is not driven by its gains"
        else:
            continue
        found.append((name, (
            f"scene['{name}'], the copy of {', '.join(gains)} the render reads, {why}: the "
            "render reads wrong gains; Repair writes it again")))
    return found


def has_packs(scene):
    """True when ``scene`` holds all three packs (the groups read them)."""
    return all(name in scene for name in PACK_NAMES)
