"""Precomputed radiance transfer (Sloan, Kautz and Snyder 2002) for the SH lighting: ``bake``
(Cycles bakes T_lm per face corner into colour attributes), ``stale`` (the attributes, the
record and whether the bake still fits the scene), ``basis`` (the worlds emitting Y_lm),
``nodes`` (the "SH Transfer" group, E = Σ T_lm L_lm), ``apply`` (the group in materials)."""
