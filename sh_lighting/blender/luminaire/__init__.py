"""Measured luminaires (IES, EULUMDAT): Blender's IES node in Cycles, fitted lamps in EEVEE."""
