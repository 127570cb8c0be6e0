"""Maps of a parameter sweep (needs matplotlib: ``pip install 'mechderive[plot]'``).

A sweep's result is a table: one row per point, with a column per swept axis (floats), ``status``
(``"ok"`` or ``"refused: <reason>"``) and a column per quantity — numbers (NaN where not available)
or, for a categorical quantity such as ``motion_class``, names (``""`` or None where not available).
:func:`plot_map` draws one quantity over 1 to 3 of the axes:

- 1 axis: the quantity against the axis (a line), or a strip of colours for a categorical one;
- 2 axes on a grid: an image, one cell per point, the cell edges halfway between the axis values,
  the first axis across and the second up;
- 3 axes on a grid: small multiples, one such image per value of the first axis (at most
  :data:`MAX_PANELS`, evenly chosen), each titled ``name = value unit``;
- random samples (``grid=False``) over 2 or 3 axes: the points over the first two axes (a third
  axis is named in the default title, not drawn).

Numbers are coloured with viridis and one colour bar (``quantity [unit]``) shared by the panels;
categories get one colour each, in the sorted order of their names, and one legend.  Refused points
and points without a value are light grey, "refused / n/a" in the legend.

What is drawn (panels, categories and their counts, colour-scale limits) is decided from the table
alone by :func:`_layout`, without matplotlib.  The picture is written to a temporary file renamed
into place (:func:`mechderive.scenes.output.atomic_output`): never half a file under ``path``.
matplotlib is imported inside :func:`plot_map` only and used through its object interface on the
Agg canvas: no pyplot, no change to the caller's backend or global figure list.
"""

from __future__ import annotations

import math
import numbers
import os
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Mapping, Sequence

import numpy as np

from ..errors import InvalidInputError, ShapeError
from ..scenes.output import atomic_output, check_output_path

__all__ = ["MAX_PANELS", "MISSING_LABEL", "PLOT_SUFFIXES", "plot_map"]

PLOT_SUFFIXES = (".png", ".pdf", ".svg")
#: the most panels a 3-axis grid gets (one per value of the first axis, evenly chosen)
MAX_PANELS = 12
MISSING_LABEL = "refused / n/a"
STATUS = "status"

_MISSING_COLOUR = "#d3d3d3"  # light grey
_MISSING_MATPLOTLIB = "plotting a sweep needs matplotlib: pip install 'mechderive[plot]'"
_NO_UNITS: Mapping[str, str] = MappingProxyType({})


@dataclass(frozen=True, eq=False)
class _Layout:
    """What :func:`plot_map` draws, decided from the table alone.

    ``values`` holds the points shown: on a grid shaped by the axes (3 axes: the panels' slices
    only, ``(panels, n1, n2)``), for random samples in row order (1 axis: sorted by the axis).
    A numeric quantity is float with NaN where refused or not available; a categorical one is the
    index into ``categories``, -1 where refused or not available.
    """

    axes: tuple[str, ...]
    quantity: str
    grid: bool
    #: per axis: its sorted values (grid) or its column in the order of ``values`` (random)
    coords: tuple[np.ndarray, ...]
    values: np.ndarray
    panels: int
    #: the first axis' value of each panel (3 axes on a grid), else ()
    panel_values: tuple[float, ...]
    categorical: bool
    #: (name, points shown) in drawing order, the names sorted; () for a numeric quantity
    categories: tuple[tuple[str, int], ...]
    #: points shown that are refused or have no value
    missing: int
    #: (lowest, highest) value shown of a numeric quantity; None if categorical or nothing to show
    limits: tuple[float, float] | None


def _import_matplotlib() -> tuple[Any, Any, Any]:
    try:
        import matplotlib
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as exc:
        raise InvalidInputError(_MISSING_MATPLOTLIB) from exc
    return matplotlib, Figure, FigureCanvasAgg


def _column(table: Mapping[str, Any], name: str, rows: int | None) -> np.ndarray:
    column = np.asarray(table[name])
    if column.ndim != 1 or (rows is not None and column.shape[0] != rows):
        raise ShapeError(f"expected column {name!r} to be 1-D with one entry per row"
                         f"{'' if rows is None else f' ({rows})'}, got shape {column.shape}")
    return column


def _check_names(table: Any, axes: Any, quantity: Any) -> tuple[str, ...]:
    if not isinstance(table, Mapping):
        raise InvalidInputError(f"expected `table` to be a mapping column name -> 1-D array, "
                                f"got {type(table).__name__}")
    if isinstance(axes, str) or not isinstance(axes, Sequence) or not all(isinstance(a, str) for a in axes):
        raise InvalidInputError(f"expected `axes` to be a sequence of 1 to 3 column names, got {axes!r}")
    axes = tuple(axes)
    if not 1 <= len(axes) <= 3:
        raise InvalidInputError(f"expected 1 to 3 axes, got {len(axes)} ({', '.join(axes) or 'none'})")
    if len(set(axes)) != len(axes):
        raise InvalidInputError(f"expected distinct axes, got {', '.join(axes)}")
    columns = [k for k in table if k != STATUS]
    for a in axes:
        if a not in columns:
            raise InvalidInputError(f"unknown axis {a!r}: expected a column of the table, one of "
                                    f"{', '.join(map(str, columns)) or 'none'}")
    quantities = [k for k in columns if k not in axes]
    if not isinstance(quantity, str) or quantity not in quantities:
        what = "an axis, not a quantity" if quantity in axes else "unknown quantity"
        raise InvalidInputError(f"{what} {quantity!r}: expected a column of the table other than the axes "
                                f"and {STATUS!r}, one of {', '.join(map(str, quantities)) or 'none'}")
    return axes


def _ok(table: Mapping[str, Any], rows: int) -> np.ndarray:
    """True where the point was computed (``status`` "ok"); every point when there is no status."""
    if STATUS not in table:
        return np.ones(rows, dtype=bool)
    return np.array([isinstance(s, str) and s.strip() == "ok" for s in _column(table, STATUS, rows).tolist()],
                    dtype=bool)


def _is_number(x: Any) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool)


def _read_quantity(name: str, column: np.ndarray, ok: np.ndarray) -> tuple[bool, np.ndarray]:
    """(categorical?, values): floats with NaN for missing, or an object array of names, None for missing."""
    if column.dtype.kind in "biuf":
        values = column.astype(float)
    elif column.dtype.kind in "US":
        values = np.array([str(x) or None for x in column.tolist()], dtype=object)
        values[~ok] = None
        return True, values
    elif column.dtype.kind == "O":
        items = column.tolist()
        if any(isinstance(x, str) for x in items):
            bad = [x for x in items if not (x is None or isinstance(x, str) or (_is_number(x) and math.isnan(x)))]
            if bad:
                raise InvalidInputError(f"expected quantity {name!r} to hold names (\"\" or None where not "
                                        f"available) or numbers, got names mixed with {bad[0]!r}")
            values = np.array([x if isinstance(x, str) and x else None for x in items], dtype=object)
            values[~ok] = None
            return True, values
        bad = [x for x in items if not (x is None or _is_number(x))]
        if bad:
            raise InvalidInputError(f"expected quantity {name!r} to hold numbers or names, got {bad[0]!r}")
        values = np.array([np.nan if x is None else float(x) for x in items], dtype=float)
    else:
        raise InvalidInputError(f"expected quantity {name!r} to hold real numbers or names, got dtype {column.dtype}")
    values[~ok | ~np.isfinite(values)] = np.nan
    return False, values


def _grid_coords(axes: tuple[str, ...], columns: list[np.ndarray]) -> tuple[np.ndarray, ...]:
    coords = tuple(np.unique(c) for c in columns)
    shape = tuple(len(c) for c in coords)
    rows = columns[0].shape[0]
    if math.prod(shape) != rows:
        sizes = " × ".join(f"{n} {a}" for n, a in zip(shape, axes))
        raise InvalidInputError(f"grid=True: expected a full grid, {sizes} = {math.prod(shape)} rows, got {rows} "
                                f"rows (pass grid=False for random samples)")
    for a, column, full in zip(axes, columns, np.meshgrid(*coords, indexing="ij")):
        wrong = np.flatnonzero(column != full.ravel())
        if wrong.size:
            i = int(wrong[0])
            raise InvalidInputError(f"grid=True: expected the rows in C order over {', '.join(axes)} (the last "
                                    f"varying fastest, each increasing), got {a} = {column[i]!r} at row {i} where "
                                    f"{full.ravel()[i]!r} belongs (pass grid=False for random samples)")
    return coords


def _panel_indices(n: int) -> np.ndarray:
    if n <= MAX_PANELS:
        return np.arange(n)
    # (n - 1) / (MAX_PANELS - 1) > 1 apart, so the rounded indices are distinct
    return np.round(np.linspace(0, n - 1, MAX_PANELS)).astype(int)


def _layout(table: Mapping[str, Any], axes: Sequence[str], quantity: str, grid: bool) -> _Layout:
    """Check the table and decide what :func:`plot_map` draws (see :class:`_Layout`)."""
    axes = _check_names(table, axes, quantity)
    if not isinstance(grid, (bool, np.bool_)):
        raise InvalidInputError(f"expected `grid` to be True or False, got {grid!r}")
    rows = _column(table, axes[0], None).shape[0]
    if rows == 0:
        raise InvalidInputError("expected a table with at least one row, got none")
    columns = []
    for a in axes:
        column = _column(table, a, rows)
        if column.dtype.kind not in "biuf" or not np.all(np.isfinite(column.astype(float))):
            raise InvalidInputError(f"expected axis {a!r} to hold finite real numbers, got "
                                    f"{column.dtype.name} values {column[:3].tolist()!r}…")
        columns.append(column.astype(float))
    categorical, values = _read_quantity(quantity, _column(table, quantity, rows), _ok(table, rows))

    panel_values: tuple[float, ...] = ()
    if grid:
        coords = _grid_coords(axes, columns)
        values = values.reshape(tuple(len(c) for c in coords))
        panels = 1
        if len(axes) == 3:
            chosen = _panel_indices(len(coords[0]))
            values = values[chosen]
            panel_values = tuple(float(v) for v in coords[0][chosen])
            panels = len(chosen)
    else:
        coords = tuple(columns)
        if len(axes) == 1:
            # stable, so that equal abscissae keep the sweep's order
            order = np.argsort(columns[0], kind="stable")
            coords, values = (columns[0][order],), values[order]
        panels = 1

    if categorical:
        names = sorted({v for v in values.ravel().tolist() if v is not None})
        index = {n: i for i, n in enumerate(names)}
        codes = np.array([-1 if v is None else index[v] for v in values.ravel().tolist()], dtype=int)
        counts = np.bincount(codes[codes >= 0], minlength=len(names))
        return _Layout(axes, quantity, bool(grid), coords, codes.reshape(values.shape), panels, panel_values, True,
                       tuple((n, int(c)) for n, c in zip(names, counts)), int(np.sum(codes < 0)), None)
    finite = values[np.isfinite(values)]
    limits = (float(finite.min()), float(finite.max())) if finite.size else None
    return _Layout(axes, quantity, bool(grid), coords, values, panels, panel_values, False, (),
                   int(values.size - finite.size), limits)


def _check_units(units: Any) -> Mapping[str, str]:
    if not isinstance(units, Mapping) or not all(isinstance(k, str) and isinstance(v, str) for k, v in units.items()):
        raise InvalidInputError(f"expected `units` to be a mapping column name -> unit string, got {units!r}")
    return units


def _label(name: str, units: Mapping[str, str]) -> str:
    unit = units.get(name, "")
    return f"{name} [{unit}]" if unit else name


def _edges(v: np.ndarray) -> np.ndarray:
    """Cell edges halfway between the values, the outer cells as wide as their neighbours."""
    if v.size == 1:
        half = 0.5 * abs(v[0]) if v[0] != 0 else 0.5
        return np.array([v[0] - half, v[0] + half])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate(([2 * v[0] - mid[0]], mid, [2 * v[-1] - mid[-1]]))


def _palette(mpl: Any, k: int) -> list[Any]:
    if k <= 10:
        return list(mpl.colormaps["tab10"].colors[:k])
    if k <= 20:
        return list(mpl.colormaps["tab20"].colors[:k])
    return [mpl.colormaps["turbo"](x) for x in np.linspace(0.05, 0.95, k)]


@dataclass(frozen=True)
class _Colours:
    cmap: Any
    norm: Any
    handles: list[Any]  # legend patches: the categories, then "refused / n/a" if any point is


def _colours(mpl: Any, layout: _Layout) -> _Colours:
    from matplotlib.colors import BoundaryNorm, ListedColormap, Normalize
    from matplotlib.patches import Patch

    missing = [Patch(facecolor=_MISSING_COLOUR, edgecolor="0.5", label=MISSING_LABEL)] if layout.missing else []
    if layout.categorical:
        k = len(layout.categories)
        if k == 0:
            return _Colours(ListedColormap([_MISSING_COLOUR]).with_extremes(bad=_MISSING_COLOUR),
                            Normalize(0.0, 1.0), missing)
        colours = _palette(mpl, k)
        cmap = ListedColormap(colours).with_extremes(bad=_MISSING_COLOUR)
        patches = [Patch(facecolor=c, label=name) for c, (name, _) in zip(colours, layout.categories)]
        return _Colours(cmap, BoundaryNorm(np.arange(k + 1) - 0.5, k), patches + missing)
    low, high = layout.limits if layout.limits is not None else (0.0, 1.0)
    return _Colours(mpl.colormaps["viridis"].with_extremes(bad=_MISSING_COLOUR), Normalize(low, high), missing)


def _masked(layout: _Layout, values: np.ndarray) -> np.ma.MaskedArray:
    return np.ma.masked_array(values, mask=(values < 0) if layout.categorical else ~np.isfinite(values))


def _image(ax: Any, layout: _Layout, colours: _Colours, values: np.ndarray) -> Any:
    x, y = layout.coords[-2], layout.coords[-1]
    # values[i, j] is at (x[i], y[j]); pcolormesh wants rows along y
    return ax.pcolormesh(_edges(x), _edges(y), _masked(layout, values).T, cmap=colours.cmap, norm=colours.norm,
                         shading="flat")


def _scatter(ax: Any, layout: _Layout, colours: _Colours) -> Any:
    x, y, values = layout.coords[0], layout.coords[1], layout.values
    size = float(np.clip(4000.0 / values.size, 4.0, 36.0))
    bad = (values < 0) if layout.categorical else ~np.isfinite(values)
    ax.scatter(x[bad], y[bad], s=size, color=_MISSING_COLOUR, edgecolors="none")
    return ax.scatter(x[~bad], y[~bad], s=size, c=values[~bad], cmap=colours.cmap, norm=colours.norm,
                      edgecolors="none")


def _line(ax: Any, layout: _Layout, units: Mapping[str, str]) -> None:
    x, values = layout.coords[0], layout.values
    ax.plot(x, values, marker=".", color="C0")  # NaN leaves a gap
    bad = ~np.isfinite(values)
    if bad.any():
        # at the foot of the axes: a refused point has no height
        ax.plot(x[bad], np.full(int(bad.sum()), 0.03), "x", color="0.6", transform=ax.get_xaxis_transform())
    ax.set_ylabel(_label(layout.quantity, units))
    ax.grid(True, alpha=0.3)


def _strip(ax: Any, layout: _Layout, colours: _Colours) -> None:
    ax.pcolormesh(_edges(layout.coords[0]), [0.0, 1.0], _masked(layout, layout.values)[None, :],
                  cmap=colours.cmap, norm=colours.norm, shading="flat")
    ax.set_yticks([])


def _default_title(layout: _Layout) -> str:
    title = f"{layout.quantity} over {' × '.join(layout.axes)}"
    if not layout.grid and len(layout.axes) == 3:
        title += f" ({layout.axes[2]} not shown)"
    return title


def _figure_size(layout: _Layout) -> tuple[float, float]:
    if len(layout.axes) == 1:
        return (6.5, 2.6) if layout.categorical else (6.5, 4.2)
    if layout.panels == 1:
        return 6.5, 4.8
    cols = math.ceil(math.sqrt(layout.panels))
    return 2.6 * cols + 2.0, 2.3 * math.ceil(layout.panels / cols) + 0.9


def _draw(fig: Any, mpl: Any, layout: _Layout, units: Mapping[str, str]) -> None:
    colours = _colours(mpl, layout)
    mappable = None
    if len(layout.axes) == 1:
        ax = fig.add_subplot(1, 1, 1)
        if layout.categorical:
            _strip(ax, layout, colours)
        else:
            _line(ax, layout, units)
        ax.set_xlabel(_label(layout.axes[0], units))
        all_axes = [ax]
    elif layout.panels == 1:
        ax = fig.add_subplot(1, 1, 1)
        if layout.grid:
            mappable = _image(ax, layout, colours, layout.values)
        else:
            mappable = _scatter(ax, layout, colours)
            ax.grid(True, alpha=0.3)
        ax.set_xlabel(_label(layout.axes[0], units))
        ax.set_ylabel(_label(layout.axes[1], units))
        all_axes = [ax]
    else:
        cols = math.ceil(math.sqrt(layout.panels))
        grid = fig.subplots(math.ceil(layout.panels / cols), cols, sharex=True, sharey=True, squeeze=False)
        all_axes = list(grid.ravel()[: layout.panels])
        for extra in grid.ravel()[layout.panels:]:
            extra.set_visible(False)
        unit = units.get(layout.axes[0], "")
        for ax, value, values in zip(all_axes, layout.panel_values, layout.values):
            mappable = _image(ax, layout, colours, values)
            ax.set_title(f"{layout.axes[0]} = {value:.4g}{f' {unit}' if unit else ''}", fontsize="small")
        fig.supxlabel(_label(layout.axes[1], units))
        fig.supylabel(_label(layout.axes[2], units))
    if not layout.categorical and mappable is not None:
        fig.colorbar(mappable, ax=all_axes, label=_label(layout.quantity, units))
    handles = colours.handles
    if len(layout.axes) == 1 and not layout.categorical and layout.missing:
        from matplotlib.lines import Line2D

        handles = [Line2D([], [], linestyle="none", marker="x", color="0.6", label=MISSING_LABEL)]
    if handles:
        fig.legend(handles=handles, loc="outside right upper", fontsize="small", frameon=False)


def plot_map(table: Mapping[str, np.ndarray], axes: Sequence[str], quantity: str, path: str | os.PathLike, *,
             units: Mapping[str, str] = _NO_UNITS, grid: bool = True, title: str | None = None) -> None:
    """Draw ``quantity`` of a sweep's ``table`` over its ``axes`` (1 to 3 column names, in sweep order) to ``path``.

    ``table`` maps column names to 1-D arrays, one entry per sweep point: the axes (floats),
    ``status`` ("ok" or "refused: <reason>"; all ok without it) and the quantity — numbers, NaN
    where not available, or names ("" or None where not available).  With ``grid=True`` the rows
    form a full grid in C order over ``axes`` (the last varying fastest, each increasing);
    ``grid=False`` means random samples.  ``units`` maps column names to units for the labels
    (``name [unit]``); ``title`` defaults to ``"quantity over a × b"``.  ``path`` ends in .png,
    .pdf or .svg.  See the module's docstring for the layout.

    Raises :class:`~mechderive.errors.InvalidInputError` for an unknown axis or quantity, more than
    three axes, rows that are not the grid announced, an unsupported suffix or an unwritable path,
    and if matplotlib is missing.
    """
    mpl, Figure, FigureCanvasAgg = _import_matplotlib()
    layout = _layout(table, axes, quantity, grid)
    units = _check_units(units)
    if title is not None and not isinstance(title, str):
        raise InvalidInputError(f"expected `title` to be a string or None, got {title!r}")
    path = check_output_path(path, PLOT_SUFFIXES, what="plot file")
    fig = Figure(figsize=_figure_size(layout), layout="constrained")
    FigureCanvasAgg(fig)
    try:
        _draw(fig, mpl, layout, units)
        fig.suptitle(_default_title(layout) if title is None else title)
        with atomic_output(path, what="plot file") as tmp:
            fig.savefig(tmp, dpi=110, format=path.suffix.lower()[1:])
    finally:
        # the figure is in no pyplot list; clearing it frees its artists now rather than at collection
        fig.clear()
