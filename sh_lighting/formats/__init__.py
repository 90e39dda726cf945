"""File formats, numpy only (no bpy): SH presets, the interop formats of three.js, glTF and
Filament, PNG, and the atomic write that every file goes through."""
