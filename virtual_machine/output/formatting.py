"""The texts a gear engineer reads: the setting sheet and the measurement's class table (CLI and report)."""

from __future__ import annotations

from virtual_machine.setting.sheet import SetupSheet


def three_figures(x: float) -> str:
    """``x`` to three significant figures, written out (6,000, not 6e+03): a machine's limits are orders of
    magnitude, and so is how far a job is beyond them."""
    return f"{float(f'{x:.3g}'):,.0f}"


def format_sheet(sheet: SetupSheet, source: str) -> str:
    """The setting sheet as a setter reads it."""
    lines = [f"SETTING SHEET  {source}", f"structure: {sheet.structure}", ""]
    g = sheet.geometry
    if sheet.kind == "skiving":
        gear, cut = g["gear"], g["cutter"]
        kind = "internal" if gear["internal"] else "external"
        lines += [
            f"gear    z2 = {gear['z']} {kind}, mn = {gear['mn_mm']:g} mm, alpha_n = {gear['alpha_n_deg']:g} deg, "
            f"beta = {gear['beta_deg']:+g} deg, d = {gear['d_mm']:.4f}, db = {gear['db_mm']:.4f}, "
            f"da = {gear['da_mm']:.4f}, df = {gear['df_mm']:.4f} mm, lead = {gear['lead_mm']:.3f} mm",
            f"cutter  z0 = {cut['z']}, beta0 = {cut['beta_deg']:+g} deg, x0 = {cut['x']:+g}, d0 = {cut['d_mm']:.4f}, "
            f"da0 = {cut['da_mm']:.4f} mm, edge = {cut['edge']}",
            f"shaft angle Sigma = {g['shaft_angle_deg']:+.4f} deg, finishing centre distance a = "
            f"{g['centre_distance_final_mm']:.4f} mm, generated root diameter {g['generated_root_diameter_mm']:.4f} mm",
            f"speed ratio n2/n0 = {g['speed_ratio_n2_n0']:+.9f}, work speed {g['work_speed_rpm']:.2f} rpm, "
            f"differential rotation {g['differential_rotation_deg_per_mm']:+.6f} deg per mm of carriage travel (+z)",
        ]
    else:
        lines.append(
            f"thread  lead P = {g['lead_mm']:g} mm {g['hand']} hand, d = {g['diameter_mm']:g} mm, "
            f"spindle {g['spindle_speed_rpm']:.1f} rpm"
        )
    lines += ["", "settings:"]
    for name, s in sheet.settings.items():
        real = "-" if s.realised is None else f"{s.realised:.9g}"
        how = s.realisation.get("describe") or ", ".join(
            f"{k} {v}" for k, v in s.realisation.items() if k not in ("set",) and v is not None
        )
        lines.append(f"  {name:3s} = {s.value:<16.9g} {s.formula:24s} {s.organ}")
        lines.append(f"        set {real}  ({how}); error {s.relative_error:+.2e}")
        if s.effect:
            lines.append("        -> " + ", ".join(f"{k} {v:+.4g}" for k, v in s.effect.items()))
    lines += ["", "constants: " + ", ".join(f"{k} = {v:g}" for k, v in sheet.constants.items()), "", "passes:"]
    for p in sheet.passes:
        extra = (
            f"a = {p['centre_distance_mm']:.4f} mm, depth {p['depth_mm']:.3f} mm, travel {p['travel_mm']:.2f} mm, "
            if "centre_distance_mm" in p
            else ""
        )
        lines.append(f"  {p['pass']}: infeed {p['infeed_mm']:.3f} mm, {extra}time {p['time_s']:.1f} s")
    s = sheet.sanity
    lines += [
        "",
        f"sanity: cutting speed {s['cutting_speed_m_min']:.1f} m/min, total machine time {s['total_time_s']:.1f} s",
    ]
    lines += [f"note: {n}" for n in sheet.notes]
    return "\n".join(lines)


#: the ISO 1328-1 parameters of the class table, with the block of the measurement document that holds them
CLASS_ROWS = (
    ("f_p", "pitch"),
    ("F_p", "pitch"),
    ("F_alpha", "profile"),
    ("f_Halpha", "profile"),
    ("f_falpha", "profile"),
    ("F_beta", "helix"),
    ("f_Hbeta", "helix"),
    ("f_fbeta", "helix"),
)


def class_table(doc: dict) -> list[tuple[str, float, float | None, object, object]]:
    """Rows (parameter, left [um], right [um] or None, tolerance [um] or None, class or None) of a measurement."""
    iso = doc["iso1328"]
    tol, cls = iso.get("tolerances") or {}, iso.get("class") or {}
    rows = [(k, doc[b]["left"][k], doc[b]["right"][k], tol.get(k), cls.get(k)) for k, b in CLASS_ROWS]
    rows.append(("F_r", doc["runout"]["F_r"], None, tol.get("F_r"), cls.get("F_r")))
    return rows


def format_measurement(doc: dict, source: str) -> str:
    """The class table a gear engineer reads first."""
    iso = doc["iso1328"]
    wp = doc.get("workpiece") or {}
    what = source if wp.get("kind", "mesh") == "mesh" else f"{wp['kind']} of the cut (mesh: {source})"
    lines = [f"MEASUREMENT  {what}", ""]
    lines.append(f"{'parameter':10s} {'left':>9s} {'right':>9s} {'tol':>7s} {'class':>6s}")
    cls = iso.get("class") or {}
    for key, left, right, t, c in class_table(doc):
        r = f"{right:9.2f}" if right is not None else " " * 9
        lines.append(f"{key:10s} {left:9.2f} {r} {t if t is not None else '-'!s:>7} {c if c is not None else '-'!s:>6}")
    lines.append("")
    if iso.get("error"):
        lines.append(f"ISO 1328-1: {iso['error']}")
    else:
        lines.append(f"ISO 1328-1:2013 class of the gear: {cls.get('overall')}")
    prof, helix = doc["profile"], doc["helix"]
    if "C_alpha" in prof["left"]:
        designed = any(
            abs(blk[s].get(f"C_{k}_design", 0.0)) > 0
            for k, blk in (("alpha", prof), ("beta", helix))
            for s in ("left", "right")
        )
        lines.append(
            "crowning (mean over the teeth"
            + (", deviations above are against the job's [modification]" if designed else "")
            + "): "
            + ", ".join(
                f"C_{k} {s} {blk[s][f'C_{k}']:.2f} um"
                + (f" (design {blk[s][f'C_{k}_design']:.2f})" if designed else "")
                for k, blk in (("alpha", prof), ("beta", helix))
                for s in ("left", "right")
            )
        )
    th = doc["thickness"]
    ob = th["over_balls"]
    lines.append(
        f"over balls (D = {ob['ball_diameter_mm']:g} mm): M = {ob['M_dK_mm']:.4f} mm "
        f"(nominal {ob['M_dK_nominal_mm']:.4f})"
    )
    sp = th["span"]
    if sp.get("k"):
        lines.append(f"span W_{sp['k']} = {sp['W_k_mm']:.4f} mm (nominal {sp['W_k_nominal_mm']:.4f})")
    lines.append(f"tip diameter {th['tip_diameter_mm']:.4f} mm, root diameter {th['root_diameter_mm']:.4f} mm")
    mesh = doc.get("mesh")
    if mesh and mesh.get("error"):
        lines.append(f"the mesh could not be measured (the exact measurement above does not need it): {mesh['error']}")
    elif mesh:
        verdict = "within" if mesh["within_bound"] else "OUTSIDE"
        lines.append(
            f"the mesh ({mesh['triangles']} triangles, sweep error <= {mesh['sweep_bound_um']:.2f} um, "
            f"simplified within {mesh.get('simplification_um', 0.0):.2f} um) measures class "
            f"{mesh['class']}; along the traces it differs from the exact surface by at most "
            f"{mesh['trace_difference_um']:.2f} um, {verdict} its bound ({mesh['trace_bound_um']:.2f} um)"
        )
    return "\n".join(lines)


def format_gear_stl(stl: dict) -> str:
    """One line on the gear.stl written: its size, its simplification, whether it closes."""
    line = (
        f"gear.stl: {stl['triangles']:,} triangles, {stl['megabytes']:.1f} MB (the cut solid's "
        f"{stl['solid_triangles']:,} simplified within {stl['simplification_um']:.1f} um)"
    )
    if not stl["watertight"]:
        line += "; NOT watertight after writing in float32: report it with the job (the mesh measurement may fail)"
    return line


def chip_record(chip) -> dict:
    """One chip as measurement.json holds it (the dexel removal adds thickness, contact length and centroid)."""
    out = {"pass": chip.pass_index, "cutter_tooth": chip.cutter_tooth, "time_s": chip.time, "volume_mm3": chip.volume}
    if chip.thickness_max is not None:
        out.update(
            thickness_max_um=chip.thickness_max * 1e3,
            thickness_mean_um=chip.thickness_mean * 1e3,
            contact_length_mm=chip.contact_length,
            centroid_mm=list(chip.centroid),
        )
    return out


def format_removal(cut: dict, passes: int, machine_s: float) -> str:
    """One line on how the cut removed its material."""
    removal = cut.get("removal") or {"kind": "manifold"}
    head = f"\ncut: {cut['passages']} tooth passages"
    tail = f", {cut['seconds']:.1f} s wall for {machine_s:.1f} s of machine time"
    if removal["kind"] == "dexel":
        sp = removal["spacing_mm"]
        return (
            f"{head} cut from {removal['lines']:,} dexel lines ({removal['rays_per_fan']} rays per fan at "
            f"{sp['profile'] * 1e3:.0f} um, {removal['slices']} slices at {sp['face'] * 1e3:.0f} um, refined to "
            f"{sp['fine'] * 1e3:.1f} um at the faces and tip corners), {removal['crossings']:,} exact crossings; "
            f"solid in {removal['solid_seconds']:.1f} s{tail}"
        )
    err = cut["pass_sweep_error_um"][passes - 1] if cut.get("pass_sweep_error_um") else 0.0
    return (
        f"{head}, {cut['sweeps']} sweeps, {cut['subtractions']} subtractions, sweep error <= {err:.2f} um in the "
        f"finishing pass{tail}"
    )
