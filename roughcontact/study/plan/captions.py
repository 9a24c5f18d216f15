"""The caption of every figure in the report, written from the study's own settings.

A caption states what its figure draws as the configuration made it: the
meshes of its panels in their order, the surfaces per curve, the (Sk, Ku)
pairs, sigma, b, the nominal areas, the counter bodies (their ``counter`` column). Nothing in it is
fixed text that one study makes true and another false (the quick study
draws the refined mesh where the default one draws the converged mesh).
Each writer takes the :class:`~roughcontact.study.plan.cells.StudyPlan` (its study's
settings and the cells the figure draws) and the figure's name; the figure registry
(:data:`roughcontact.study.plan.figures.FIGURES`) names each figure's writer, and the
workflow passes its text to the figure rule (``params.caption``, read by
``report/figure.rst``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

from roughcontact.study.contact_records import study_columns
from roughcontact.study.counter_records import counter_name
from roughcontact.units import MPA

#: The bands of every curve against nominal pressure (Figs 7, 9, 11-14 and beyond).
BANDS = "Bands: 95 % confidence interval of the mean over the surfaces."


def join(items: Iterable[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    items = list(items)
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} and {items[-1]}"


def numbers(values: Iterable[float], unit: str = "") -> str:
    """Distinct values in their order, ``%g`` each, joined, with the unit once."""
    text = join(f"{v:g}" for v in dict.fromkeys(values))
    return f"{text} {unit}" if unit else text


def mesh_name(mesh: str) -> str:
    """The mesh preset as a caption names it."""
    return "the paper's mesh (5 uniform trilinear layers)" if mesh == "paper" else \
        f"the {mesh} mesh"


def panels(meshes: Sequence[str]) -> str:
    """Which mesh each panel shows, left to right."""
    if len(meshes) == 1:
        return f"one panel, {mesh_name(meshes[0])}"
    if len(meshes) == 2:
        return f"left {mesh_name(meshes[0])}, right {mesh_name(meshes[1])}"
    return f"from left to right {join(mesh_name(m) for m in meshes)}"


def _columns(cells) -> list[dict]:
    """Each study cell's columns (as the aggregate table has them:
    :func:`~roughcontact.study.contact_records.study_columns`) and its surface count."""
    return [{**row, "surfaces": cell.surface.count, "cap": cell.hardness}
            for row, cell in zip(study_columns(cells), cells, strict=True)]


def _surfaces(rows) -> str:
    counts = [row["surfaces"] for row in rows]
    low, high = min(counts), max(counts)
    return f"{low} surfaces per curve" if low == high else f"{low}-{high} surfaces per curve"


def _pairs(rows) -> str:
    pairs = dict.fromkeys((row["skew"], row["kurt"]) for row in rows)
    return join(f"({s:g}, {k:g})" for s, k in pairs)


def _meshes(rows) -> list[str]:
    """The meshes in the order of the cells (the order of the panels of ``plot_by_mesh``)."""
    return list(dict.fromkeys(row["mesh"] for row in rows))


def _values(rows, key: str, unit: str = "") -> str:
    """The distinct values of a column of ``rows`` (:func:`numbers`)."""
    return numbers((row[key] for row in rows), unit)


def _mesh_names(rows) -> str:
    """The meshes of ``rows`` in words, in the order of the cells."""
    return join(mesh_name(m) for m in _meshes(rows))


def _of_cells(writer: Callable) -> Callable:
    """A caption writer of ``(plan, name)`` from one of the rows of the figure's cells
    (:func:`_columns`)."""
    def caption(plan, name):
        return writer(_columns(plan.cells[name]))
    caption.__doc__ = writer.__doc__
    return caption


def _study(rows) -> str:
    """sigma, b and the mesh of a study's cells."""
    meshes = _meshes(rows)
    return (f"sigma {_values(rows, 'sigma_um', 'um')}, "
            f"b {_values(rows, 'b_mm', 'mm')}, "
            f"{join(mesh_name(m) for m in meshes)}")


def _by_mesh(title: str, rows, finding: Callable[[list[str]], str] = lambda meshes: "") -> str:
    """Figs 7, 12, 13 and the gaps: one panel per mesh of the (Sk, Ku) cells."""
    meshes = _meshes(rows)
    return (f"{title} for (Sk, Ku) = {_pairs(rows)}, sigma "
            f"{_values(rows, 'sigma_um', 'um')}, b "
            f"{_values(rows, 'b_mm', 'mm')}; {panels(meshes)}"
            f"{finding(meshes)}. {_surfaces(rows)}. {BANDS}")


def _paper_beside(verb: str) -> Callable[[list[str]], str]:
    """Fig 12's and 13's finding, where the paper's mesh is drawn beside a finer one."""
    def finding(meshes):
        others = [m for m in meshes if m != "paper"]
        if "paper" not in meshes or not others:
            return ""
        return f": the paper's mesh, locally far too stiff, {verb} it"
    return finding


def fig01(plan, name):
    s = plan.study.entry(name)
    return (f"Fig 1: regions of the Johnson families (SU, SB, SL, ST) in the (Sk, Ku) plane "
            f"of the surface, for b = {s['b_mm']:g} mm on a {s['grid']} x "
            f"{s['grid']} grid over {s['size_mm']:g} mm x {s['size_mm']:g} mm.")


def fig02(plan, name):
    s = plan.study.entry(name)
    return (f"Fig 2: minimum reachable kurtosis against skewness for b = "
            f"{numbers(s['b_mm'], 'mm')} on a {s['grid']} x {s['grid']} grid over "
            f"{s['size_mm']:g} mm x {s['size_mm']:g} mm; it depends on b / dx (the paper's "
            f"grid spacing is not stated).")


def _grid(plan) -> str:
    surfaces = plan.study.surfaces
    (nx, ny), (lx, ly) = surfaces.grid, surfaces.size_mm
    return f"{nx} x {ny} points over {lx:g} mm x {ly:g} mm"


def fig03(plan, name):
    s = plan.study.entry(name)
    return (f"Fig 3: Gaussian surfaces, sigma {s['sigma_um']:g} um, for b = "
            f"{numbers(s['b_mm'], 'mm')} ({_grid(plan)}); realised moments in the titles.")


def fig04(plan, name):
    s = plan.study.entry("fig04")
    b = s["b_mm"] if isinstance(s["b_mm"], list) else [s["b_mm"]]
    pairs = join(f"({sk:g}, {ku:g})" for sk, ku in s["moments"])
    return (f"Fig 4: surfaces with sigma {s['sigma_um']:g} um, b {' x '.join(f'{v:g}' for v in b)}"
            f" mm and (Sk, Ku) = {pairs} ({_grid(plan)}), target and realised moments in "
            f"the titles.")


def fig05(plan, name):
    count = plan.figure_surfaces[name][0].count
    return (f"Fig 5: height distributions of the Fig 4 surfaces: the surface Fig 4 shows and "
            f"all {count} surfaces of its cell pooled, with the Johnson density of the target "
            f"moments.")


def fig07(plan, name):
    return _by_mesh("Fig 7: normalized stiffness k_P = (L/A_n) dF/dd against nominal pressure",
                    _columns(plan.cells[name]))


@_of_cells
def fig09(rows):
    return (f"Fig 9: mean-plane deflection d_b and asperity deflection d_a = d - d_b against "
            f"nominal pressure for (Sk, Ku) = {_pairs(rows)}, {_study(rows)}. "
            f"{_surfaces(rows)}. {BANDS}")


@_of_cells
def fig10(rows):
    where = f"sigma {_values(rows, 'sigma_um', 'um')}, b {_values(rows, 'b_mm', 'mm')}"
    return (f"Fig 10: cumulative height distributions as depth below the highest point of the "
            f"surfaces of (Sk, Ku) = {_pairs(rows)}, {where} (the Fig 9 cells), pooled over "
            f"the {_values(rows, 'surfaces')} surfaces of each.")


@_of_cells
def fig11(rows):
    b, sigma = _values(rows, "b_mm", "mm"), _values(rows, "sigma_um", "um")
    return (f"Fig 11: normalized stiffness for the correlation lengths b = {b}, surfaces of "
            f"(Sk, Ku) = {_pairs(rows)}, sigma {sigma}, {_mesh_names(rows)}. "
            f"{_surfaces(rows)}. {BANDS}")


def fig11_resolved(plan, name):
    rows = _columns(plan.cells[name])
    return (f"Beyond the paper: Fig 11 on a grid that resolves the ACF ({_grid(plan)}): "
            f"k_P, real area, peak pressure, the number of contact spots, their mean area "
            f"and the real area corrected by its perimeter, for b = "
            f"{_values(rows, 'b_mm', 'mm')}, sigma {_values(rows, 'sigma_um', 'um')}, "
            f"{_mesh_names(rows)}. {_surfaces(rows)}. {BANDS}")


def fig12(plan, name):
    return _by_mesh("Fig 12: maximum contact pressure against nominal pressure",
                    _columns(plan.cells[name]), _paper_beside("overestimates"))


def fig13(plan, name):
    return _by_mesh("Fig 13: real contact area against nominal pressure",
                    _columns(plan.cells[name]), _paper_beside("underestimates"))


@_of_cells
def fig14(rows):
    areas = join(f"{size:g} mm x {size:g} mm" for size in dict.fromkeys(r["size_mm"] for r in rows))
    return (f"Fig 14: normalized stiffness for the nominal areas {areas} on the same contact "
            f"elements, surfaces of (Sk, Ku) = {_pairs(rows)}, sigma "
            f"{_values(rows, 'sigma_um', 'um')}, b "
            f"{_values(rows, 'b_mm', 'mm')}, nu = "
            f"{_values(rows, 'nu')}. {_surfaces(rows)}. {BANDS}")


def gaps(plan, name):
    return _by_mesh("Beyond the paper: the mean gap (mean interfacial separation) against "
                    "nominal pressure", _columns(plan.cells[name]))


def table_eu(plan, name):
    rows = _columns(plan.cells[name])
    return (f"Mean-plane modulus E_u = P L / d_b (Eq 36) for nu = "
            f"{_values(rows, 'nu')} (for nu = 0 it equals E), surfaces of "
            f"(Sk, Ku) = {_pairs(rows)}, {_mesh_names(rows)}, as a "
            f"table (also {name}.csv): per cell, the mean over its "
            f"{_values(rows, 'surfaces')} surfaces with their standard deviation.")


def hardness(plan, name):
    rows = _columns(plan.cells[name])
    caps = sorted({r["cap"] for r in rows if r["cap"] is not None})
    capped = [m for m in _meshes(rows) if any(r["cap"] is not None and r["mesh"] == m
                                                for r in rows)]
    H = numbers((c / MPA for c in caps), "MPa")
    return (f"Beyond the paper: k_P, real area and peak pressure of the cells (Sk, Ku) = "
            f"{_pairs(rows)}, elastic (solid) and with the pressure capped at H = {H} (dashed, "
            f"on {join(mesh_name(m) for m in capped)}), and the validity map: the share of "
            f"the elastic real area (solid) and load (dotted) above H; one row per mesh, "
            f"{_mesh_names(rows)}. {_surfaces(rows)}. {BANDS}")


def measured(plan, name):
    cells = plan.cells[name]
    measured = [c for c in cells if c.surface.source_label]  # "measured <file>: "
    twins = [c for c in cells if not c.surface.source_label]
    what = join(dict.fromkeys(c.surface.source_label.rstrip(": ") for c in measured)) \
        if measured else "a measured surface"
    twin = (f"against its synthetic twin (the same sigma, Sk, Ku and correlation lengths, "
            f"{twins[0].surface.count} generated surfaces)" if twins
            else "alone (compare_synthetic: false)")
    return (f"The {what} {twin}: height maps, height distributions and spectra, and k_P, "
            f"real area and peak pressure against nominal pressure.")


def two_bodies(plan, name):
    parts = []
    for study in plan.study.entry(name)["studies"]:
        rows = _columns(plan.cells[study])
        body = (f"first body: sigma {_values(rows, 'sigma_um', 'um')}, E "
                f"{_values(rows, 'E_MPa', 'MPa')}, nu "
                f"{_values(rows, 'nu')}, a "
                f"{_values(rows, 'thickness_mm', 'mm')} block on "
                f"{_mesh_names(rows)}")
        counters = join(f"the {name}" for name in dict.fromkeys(map(counter_name, rows)))
        parts.append(f"{study} ({body}) against {counters}")
    rows = [row for study in plan.study.entry(name)["studies"]
            for row in _columns(plan.cells[study])]
    return (f"Beyond the paper: two rough, elastic bodies (Eq 17-18), one row per study: "
            f"{'; '.join(parts)}. Columns: k_P, real area, mean gap, and each body's share "
            f"of the mean-plane deflection (the counter body's solid, the first body's "
            f"dashed with crosses) against nominal pressure. {_surfaces(rows)}. {BANDS}")


def _open_faces(plan, studies) -> str:
    """Which levels of each study lie below the pressure drop (the faces would open), in
    MPa (:func:`~roughcontact.study.plan.flow_checks.open_levels_MPa`)."""
    from roughcontact.study.plan.flow_checks import open_levels_MPa

    drop = plan.study.flow.written()["pressure_drop_MPa"]
    parts = []
    for study in studies:
        p_min, p_max = plan.study.section(study).pressure_MPa
        opened = open_levels_MPa(plan.study, p_min, p_max)
        parts.append(f"{study} at {_levels(opened)}" if opened else f"{study} at no level")
    return (f"Shaded grey and hatched: the levels at which the pressure drop of "
            f"{drop:g} MPa exceeds the nominal contact pressure, so the fluid would lift the "
            f"faces apart ({'; '.join(parts)}; the tables' faces_open): the model does not "
            f"load the faces with the fluid's pressure, so its leak rate there is that of "
            f"faces held shut, not the seal's.")


def _levels(levels_MPa) -> str:
    """Pressure levels [MPa] in a caption: each to 3 significant digits."""
    return f"{join(f'{p:.3g}' for p in levels_MPa)} MPa"


def _studies_tail(plan, studies) -> str:
    """The end of a caption of the studies a figure lists: surfaces, steps, levels,
    bands."""
    rows = [row for study in studies for row in _columns(plan.cells[study])]
    contact = plan.study.contact
    return (f"{_surfaces(rows)}, {contact.steps} steps each, {contact.pressure_levels} "
            f"pressure levels. {BANDS}")


def _listed_study(study: str, rows, extra: str = "") -> str:
    """A study a figure of studies lists, in words: its sigma, b, E, nu, block and mesh,
    ``extra`` and its (Sk, Ku) pairs."""
    return (f"{study} (sigma {_values(rows, 'sigma_um', 'um')}, b "
            f"{_values(rows, 'b_mm', 'mm')}, E {_values(rows, 'E_MPa', 'MPa')}, nu "
            f"{_values(rows, 'nu')}, a {_values(rows, 'thickness_mm', 'mm')} block on "
            f"{_mesh_names(rows)}{extra}; (Sk, Ku) = {_pairs(rows)})")


def leakage(plan, name):
    flow = plan.study.flow
    ordered = [d for d in ("x", "y") if d in flow.directions]  # as the figure draws them
    directions = join(ordered)
    seal = (f"a fluid of {flow.seal_text()} (steady Reynolds equation, local cubic law, "
            f"{flow.probe.face_rule.name} face rule, {flow.probe.sides} sides; along "
            f"{directions}{', y dashed' if len(ordered) > 1 else ''})")
    parts = []
    studies = plan.study.entry(name)["studies"]
    for study in studies:
        parts.append(_listed_study(study, _columns(plan.cells[study])))
    return (f"Beyond the paper: will the seal leak? The flow of {seal}, one row per study: "
            f"{'; '.join(parts)}. Columns: the leak rate Q against nominal pressure (log "
            f"axes: the levels where Q > 0 only; Q is 0 once every surface has sealed), the "
            f"flow factor phi = K / mean gap^3 against nominal pressure, phi against the "
            f"real area fraction (the cells' mean curves, log, where phi > 0) with each "
            f"cell's percolation threshold (the real area at which half its surfaces have "
            f"sealed; along {ordered[0]} a line in the cell's colour, its 95 % band "
            f"shaded{', along y dotted' if len(ordered) > 1 else ''}) and Dapp et "
            f"al. 2012's 0.42 (grey dashed), and the share of surfaces still leaking. "
            f"Each cell's sealing pressure along {ordered[0]} (the nominal pressure at which "
            f"half its surfaces have sealed): a dash-dot line in its colour on the leak "
            f"rate and on the share still leaking, its 95 % band shaded on the latter, its "
            f"value and band in MPa in that panel's legend and after this caption (the "
            f"sidecar's flow.percolation). {_open_faces(plan, studies)} Each curve is "
            f"labelled by its study and (Sk, Ku) and, where a study's cells share them, "
            f"what tells them apart. Hollow markers: a level resting on fewer surfaces than "
            f"the cell has (its band is not to be read as a tight one). "
            f"{_studies_tail(plan, studies)}")


def conductance(plan, name):
    studies = plan.study.entry(name)["studies"]
    parts = []
    for study in studies:
        rows = _columns(plan.cells[study])
        caps = sorted({row["cap"] / 1e6 for row in rows if row["cap"] is not None})
        parts.append(_listed_study(study, rows, f", the pressure capped at "
                                   f"{numbers(caps, 'MPa')}" if caps else ""))
    return (f"Beyond the paper: how much heat crosses the interface? The thermal contact "
            f"conductance of a body of {plan.study.conductance.material_text()} pressed on "
            f"a smooth flat, {plan.study.conductance.counter_text()} (isothermal spots, no "
            f"flux elsewhere; the block's base isothermal, its sides insulated): "
            f"{'; '.join(parts)}. "
            f"Left: h_c = C / A_n (solid) and the spots' constriction alone, h_s = 1 / "
            f"(A_n (1/C - R_bulk)) (dotted), against nominal pressure for each cell of "
            f"{studies[0]}, with Mikic's (1974) elastic correlation h = 1.54 k_s (m / "
            f"sigma) (sqrt(2) P / (E* m))^0.94 (dashed, k_s = 2 k1 k2 / (k1 + k2), 2 k "
            f"against a perfect conductor, E* = E / (1 - nu^2), m the cell's rms profile "
            f"slope at the grid's spacing, sigma its rms height). Middle: h_s over the "
            f"correlation of each cell of every study (Cooper, Mikic and Yovanovich's "
            f"(1969) plastic h = 1.25 k_s (m / sigma) (P / H)^0.95 for capped cells, H the "
            f"cap). Right: the bulk's share of the resistance, R_bulk C, against nominal "
            f"pressure (R_bulk = L / (k A_n)). "
            f"{_studies_tail(plan, studies)}")


def _unloading(loading) -> str:
    """Where each cycle of the ``loading`` section unloads to, in words."""
    if not loading.unload_to:
        return "back to no load"
    return f"down to {loading.unload_to:g} of it"


def _cycles_right_panel(plan) -> str:
    """The third panel of the cycles figure: the leak rate with the flow on, else the
    permanent set."""
    flow = plan.study.flow
    if not flow.enabled:
        return ("Right: the permanent set (the approach at which the flattened surface "
                "first touches: the residual approach once unloaded, from the virgin "
                "surface's first touch) against load step, in the same line styles, the "
                "end of each cycle marked by a grey vertical line.")
    ordered = [d for d in ("x", "y") if d in flow.directions]
    drop = flow.written()["pressure_drop_MPa"]
    return (f"Right: the leak rate Q of a fluid of {flow.seal_text()} (steady Reynolds "
            f"equation, local cubic law) along {ordered[0]}, on a log axis, against "
            f"nominal pressure in the same line styles, so that the loading curve and the "
            f"unloading curve beside it give the leak rate at the same load pressed once "
            f"and pressed before; its band is drawn in log space. Grey crosses: the levels "
            f"at which the pressure drop of {drop:g} MPa exceeds the nominal contact "
            f"pressure (the tables' faces_open), where the fluid would lift the faces "
            f"apart: the model does not load the faces with the fluid's pressure, so its "
            f"leak rate there is that of faces held shut.")


def cycles(plan, name):
    loading = plan.study.loading
    studies = plan.study.entry(name)["studies"]
    parts, rows = [], []
    for study in studies:
        capped = [cell for cell in plan.cells[study] if loading.applies(cell)]
        study_rows = _columns(capped)
        rows += study_rows
        peaks = sorted({cell.pressure_range[1] / MPA for cell in capped})
        caps = sorted({row["cap"] / MPA for row in study_rows})
        parts.append(_listed_study(study, study_rows, f", capped at {numbers(caps, 'MPa')}, "
                                   f"its peak {numbers(peaks, 'MPa')}"))
    cycle_words = {1: "once", 2: "twice"}.get(loading.cycles, f"{loading.cycles} times")
    flow = plan.study.flow
    leak = (f", the leak rate along {[d for d in ('x', 'y') if d in flow.directions][0]} "
            f"at half the peak on loading and on unloading (and their ratio)"
            if flow.enabled else "")
    unclosed = (" (the first cycle ends above no load, so its work also holds the elastic "
                "energy stored at its end)" if loading.unload_to > 0 else "")
    shaken = (" and the share of its surfaces shaken down (no plastic volume added) in the "
              "second cycle" if loading.cycles > 1 else "")
    return (f"Beyond the paper: loading, unloading and reloading. Each capped cell is "
            f"pressed under load control (every surface at the same nominal pressure at "
            f"each step) from no load up to its highest pressure level and "
            f"{_unloading(loading)}, {cycle_words}, in {loading.steps} equal load steps per "
            f"leg, the pressure capped at the hardness and the cap's permanent set (the "
            f"surface flattened where it sat at the cap) kept from step to step; one row "
            f"of panels per study: {'; '.join(parts)}. Each cell in its own colour, "
            f"labelled by its study and (Sk, Ku) (and what tells a study's cells apart); "
            f"in every panel the first loading is solid, each unloading dashed and each "
            f"reloading dotted (drawn wider, so that where it retraces the unloading, an "
            f"elastic cycle, its dots show on the dashes), each leg from the last step of "
            f"the one before. "
            f"Left: nominal pressure against the approach d (from the virgin surface's "
            f"first touch; the loop's area is the energy the cycle dissipated), the band "
            f"the 95 % confidence interval of the mean approach at each step's pressure "
            f"(shaded across the approach). Middle: the stiffness per nominal area k_P = "
            f"(dF/dd) / A_n (the tangent on the elements in contact below the cap) against "
            f"nominal pressure, with its band, its legs not joined (a tangent jumps where "
            f"the load turns): unloading is stiffer than loading once the spots have "
            f"yielded. {_cycles_right_panel(plan)} After this caption, each "
            f"cell's residual approach after the first cycle, its unloading-to-loading "
            f"stiffness ratio at half the peak, the energy each cycle dissipated beside the "
            f"plastic work{unclosed}{shaken}{leak}, with their bands. {_surfaces(rows)}. "
            f"{BANDS}")
