"""Sweeps: a scene's per-motion quantities over a grid or a random sample of its values (``mechderive sweep``).

:mod:`.spec` reads the sweep file, :mod:`.evaluate` computes one chunk (the system's NumPy batch,
the planner for the points it does not answer), :mod:`.run` runs the chunks here, in a local pool or on
Dask and writes them as they finish (:mod:`.table`), :mod:`.plot` draws the map.
"""
