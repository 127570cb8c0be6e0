"""The heavy symmetric top, section 3.6: a top pinned at a point, acted on by gravity.

:mod:`.model` holds the symbolic model, derived through the generic Lagrangian layer
(:mod:`mechderive.core.lagrangian`): ``from mechderive.systems.heavy_top.model import model``.
"""
