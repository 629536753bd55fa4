"""Tables (markdown), JSON and the plot of bench/anchors, from the merged results."""
import json

ROWS = [  # (row name, label); the names of `robodiff bench --json` and anchors_bench
    ("rnea_value", "RNEA value"),
    ("rnea_jacobian_dense", "RNEA value + J"),
    ("aba_value", "ABA value"),
    ("aba_jacobian", "ABA value + J"),
    # robodiff's side through --spec (builtin_rows.py)
    ("crba_value", "CRBA value"),
    ("frame_jacobian_value", "frame Jacobian value"),
    # user-function rows (step_rows.hpp, step_specs.py); CppADCodeGen, CasADi, MuJoCo: fixed base only
    ("euler_step_value", "Euler step value"),
    ("euler_step_jacobian", "Euler step + J"),
    ("step_cost_value", "step + cost value"),
    ("step_cost_derivatives", "step + cost + derivatives"),
]
STEP_ROWS = ["euler_step_value", "euler_step_jacobian", "step_cost_value", "step_cost_derivatives"]
BUILD_ROWS = ["rnea_value", "rnea_jacobian_dense", "aba_value", "aba_jacobian", "crba_value",
              "frame_jacobian_value"] + STEP_ROWS
# the sides, in the tables' column order (robodiff last), and their titles
SIDE_TITLES = {"pinocchio": "Pinocchio", "cppadcodegen": "CppADCodeGen", "casadi": "CasADi", "crocoddyl": "crocoddyl",
               "mujoco": "MuJoCo", "robodiff": "robodiff"}
# the sides that build a library per row, in the build table's column order
BUILDERS = ["cppadcodegen", "casadi", "robodiff"]
SIDES = list(SIDE_TITLES)
# the step rows of the generated-code sides, which tape q as its own tangent (nq = nv): on a
# fixed base only (MuJoCo's euler_step rows say so themselves, mujoco_side.py)
FIXED_BASE_STEP_ROWS = {side: ["euler_step_value", "euler_step_jacobian", "step_cost_value"]
                        for side in ("cppadcodegen", "casadi")}
ANCHORS = [s for s in SIDES if s != "robodiff"]


def cell(entry):
    """A side's cell of the speed table: µs, or why there is none."""
    if entry is None:
        return "–"
    if entry.get("us") is not None:
        return fmt(entry["us"])
    return entry.get("note") or entry.get("status", "–")


def fmt(x, digits=3):
    if x is None:
        return "–"
    if x >= 100:
        return f"{x:,.0f}"
    return f"{x:.{digits}g}"


def ratio_to_best(row):
    rd = (row.get("robodiff") or {}).get("us")
    anchors = [(row.get(s) or {}).get("us") for s in ANCHORS]
    anchors = [a for a in anchors if a is not None]
    if rd is None or not anchors:
        return None
    return rd / min(anchors)


def step_notes(entries, name, floating_base):
    """A row's entries per side, with "fixed base only" for the generated-code sides' step
    rows on a floating base."""
    entries = dict(entries)
    for side, rows in FIXED_BASE_STEP_ROWS.items():
        if floating_base and name in rows:
            entries.setdefault(side, {"us": None, "note": "fixed base only"})
    return entries


def robot_table(result):
    lines = [f"### {result['title']} (nq {result['nq']}, nv {result['nv']})", "",
             "| function | " + " | ".join(f"{SIDE_TITLES[s]} µs" for s in SIDES) + " | robodiff / best |",
             "|---|" + "---|" * (len(SIDES) + 1)]
    for name, label in ROWS:
        row = step_notes(result["rows"].get(name, {}), name, result["floating_base"])
        r = ratio_to_best(row)
        lines.append(f"| {label} | " + " | ".join(cell(row.get(s)) for s in SIDES) +
                     f" | {'–' if r is None else f'{r:.2f}'} |")
    lines += ["", "| build (cold) | " + " | ".join(f"{SIDE_TITLES[b]} s | {SIDE_TITLES[b]} MiB" for b in BUILDERS) +
              " | robodiff / CppADCodeGen (s, MiB) |", "|---|" + "---|" * (2 * len(BUILDERS) + 1)]
    for name, label in ROWS:
        if name not in BUILD_ROWS:
            continue
        b = step_notes(result["builds"].get(name, {}), name, result["floating_base"])
        cells = []
        for builder in BUILDERS:
            e = b.get(builder, {})
            cells += [fmt(e["seconds"]) if e.get("seconds") is not None else (e.get("note") or "–"), fmt(e.get("mib"))]
        cg, rd = b.get("cppadcodegen", {}), b.get("robodiff", {})
        rs = ("–" if cg.get("seconds") is None or rd.get("seconds") is None
              else f"{rd['seconds'] / cg['seconds']:.2f}")
        rm = ("–" if cg.get("mib") is None or rd.get("mib") is None else f"{rd['mib'] / cg['mib']:.2f}")
        lines.append(f"| {label} | " + " | ".join(cells) + f" | {rs}, {rm} |")
    checks = result.get("checks", {})
    if checks:
        lines += ["", "Checks against Pinocchio's analytic outputs (max relative error, limit 1e-9): " +
                  "; ".join(f"{k} {v}" for k, v in checks.items())]
    return "\n".join(lines)


def print_tables(results, header):
    print(header)
    for result in results:
        print()
        print(robot_table(result))


def write_json(path, results, header):
    with open(path, "w") as f:
        json.dump({"header": header, "robots": results}, f, indent=1)


def plot(path, results):
    """µs per call against DoF (nv): one line per side and row kind."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    kinds = [r for r in ROWS if r[0] in BUILD_ROWS]
    cols = 4
    rows = (len(kinds) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 4 * rows), sharey=False, squeeze=False)
    axes = axes.reshape(-1)
    for ax in axes[len(kinds):]:
        ax.set_visible(False)
    styles = {"pinocchio": "o-", "cppadcodegen": "s--", "casadi": "P--", "crocoddyl": "D-.", "mujoco": "v:",
              "robodiff": "^-"}
    # one colour per side in every panel (a panel may lack some sides; one legend, in the first)
    colours = {side: f"C{k}" for k, side in enumerate(SIDES)}
    for ax, (name, label) in zip(axes, kinds):
        for side in SIDES:
            pts = sorted((res["nv"], res["rows"][name][side]["us"]) for res in results
                         if (res["rows"].get(name, {}).get(side) or {}).get("us") is not None)
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], styles.get(side, "x:"), color=colours[side],
                        label=SIDE_TITLES[side])
        ax.set_title(label)
        ax.set_xlabel("degrees of freedom (nv)")
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("µs per call")
    handles = {}
    for ax in axes:  # every side that has a point anywhere, in one legend
        for h, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, h)
    axes[0].legend(handles.values(), handles.keys())
    fig.tight_layout()
    fig.savefig(path, dpi=110)
