"""The figures and numbers of docs/examples-staged.md from the runs of the two staged examples.

Run: srdda run examples/stages/tunnel.toml --out tunnel-run
     srdda run examples/stages/wedge-cut.toml --out wedge-run
     python examples/stages/figures.py tunnel-run wedge-run   (writes docs/figures/stages-*.png)
"""
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from srdda.apps import plotting  # noqa: E402
from srdda.apps.verify.cases.slope3d import WEDGE_PLANES, wedge_solution  # noqa: E402
from srdda.io import load_model, read_results  # noqa: E402

HERE = Path(__file__).parent
FIGURES = HERE.parents[1] / "docs" / "figures"


def last_row(res, stage: dict) -> int:
    """The last recorded row inside a stage (its last step is the next stage's first: drawn after its changes)."""
    return int(np.searchsorted(res.array("step"), stage["last_step"])) - 1


def stage_table(res) -> None:
    for s in res.stages:
        print(f"| {s['name']} | {s['kind']} | {s['first_step']}-{s['last_step']} ({s['steps']}) | "
              f"{s['start_time']:.3f}-{s['end_time']:.3f} | {s['ratio']:.3g} | {s.get('reached', '')} |")


def tunnel(run: Path) -> None:
    res = read_results(run / "results.h5")
    stage_table(res)
    step, t = res.array("step"), np.asarray(res.time)
    excavation = res.stages[1]
    after = step >= excavation["first_step"]
    start = int(np.flatnonzero(after)[0])
    moved = np.linalg.norm(res.array("centroid")[after] - res.array("centroid")[start], axis=-1)
    for s in res.stages[1:]:
        rows = (step >= excavation["first_step"]) & (step <= s["last_step"])
        d = np.linalg.norm(res.array("centroid")[rows] - res.array("centroid")[start], axis=-1)
        k, b = np.unravel_index(np.argmax(d), d.shape)
        print(f"to the end of {s['name']}: largest displacement since the excavation {d.max():.3g} m "
              f"({res.block_names[b]})")
    force = res.array("bolt_force")
    print(f"bolt forces: at installation {force[step > res.stages[2]['first_step']][0]}, end {force[-1]}, "
          f"range in the earthquake {force[step >= res.stages[3]['first_step']].min():.6g}-"
          f"{force[step >= res.stages[3]['first_step']].max():.6g} N/m")
    crown = res.array("measured_position")[:, 0]
    crown_moved = np.linalg.norm(crown[after] - crown[start], axis=-1).max()
    print(f"crown point: largest displacement since the excavation {crown_moved:.3g} m")
    for name, stage in (("gravity", res.stages[0]), ("earthquake", res.stages[3])):
        fig = plotting.fig_model(res, last_row(res, stage), color="speed")
        fig.savefig(FIGURES / f"stages-tunnel-{name}.png", dpi=110)
        plt.close(fig)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True, layout="constrained")
    ax1.plot(t[after], 1e6 * (crown[after] - crown[start])[:, 1], label="crown, vertical")
    ax1.plot(t[after], 1e6 * (crown[after] - crown[start])[:, 0], label="crown, horizontal")
    ax1.plot(t[after], 1e6 * moved.max(axis=1), label="largest block displacement")
    ax1.set(ylabel="displacement since the excavation (µm)")
    ax1.legend(fontsize="small")
    for k, name in enumerate(res.bolt_names):
        ax2.plot(t, force[:, k] / 1e3, label=name)
    ax2.set(xlabel="time (s)", ylabel="bolt force (kN per m)")
    ax2.legend(fontsize="small", ncol=3)
    for ax in (ax1, ax2):
        plotting.mark_stages(ax, res)
    fig.savefig(FIGURES / "stages-tunnel-history.png", dpi=110)
    plt.close(fig)
    print(f"measured move of {moved.max():.3g} m")


def wedge(run: Path) -> None:
    res = read_results(run / "results.h5")
    stage_table(res)
    model, _ = load_model(HERE / "wedge-cut.toml")
    step, t = res.array("step"), np.asarray(res.time)
    gravity, cut, residual = res.stages
    line = wedge_solution(*WEDGE_PLANES, 45.0).line
    centroid, velocity = res.array("centroid")[:, 0], res.array("velocity")[:, 0, :3]
    start = int(np.searchsorted(step, cut["first_step"]))
    during_cut = (step >= cut["first_step"]) & (step <= cut["last_step"])
    travel = np.linalg.norm(centroid[during_cut] - centroid[start], axis=1).max()
    print(f"wedge travel during the cut stage: {travel:.3g} m")
    expected = wedge_solution(*WEDGE_PLANES, model.stages[2].joint_materials["joint"].friction_angle)
    i = int(np.searchsorted(t, residual["start_time"] + 0.05 - 5e-4))
    along = velocity @ line
    a = (along[-1] - along[i]) / (t[-1] - t[i])
    print(f"residual: acceleration along the line {a:.5f} m/s2, Hoek & Bray {expected.acceleration:.5f} "
          f"({a / expected.acceleration - 1:+.2e}); travel {(centroid[-1] - centroid[start]) @ line:.4f} m")
    # before (the end of gravity, the toe in place) and after (the end of residual); the joint-plane blocks see-through
    from srdda.apps.render3d import render_blocks

    colours = {"wedge": "tab:orange", "plane A": "0.7", "plane B": "0.55", "toe": "tan"}
    verts = res.array("vertices")
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6), layout="constrained")
    slid = (centroid[-1] - centroid[start]) @ line
    for ax, stage, what in ((axes[0], gravity, "before the cut (end of gravity), the toe in place"),
                            (axes[1], residual, f"end of residual: the wedge slid {slid:.2f} m")):
        row = last_row(res, stage)
        opacity = [0.0 if (n == "toe" and stage is residual) else 1.0 if n == "wedge" else 0.45
                   for n in res.block_names]
        ax.imshow(render_blocks(verts[row], res.mesh, colors=[colours[n] for n in res.block_names], opacity=opacity,
                                bounds=np.ravel(np.stack([verts[0].min(axis=0), verts[0].max(axis=0)]).T)))
        ax.set_axis_off()
        ax.set_title(f"{what}, t = {t[row]:.2f} s", fontsize=9)
    fig.savefig(FIGURES / "stages-wedge-3d.png", dpi=110)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    ax.plot(t, (centroid - centroid[start]) @ line, label="simulated")
    tau = np.clip(t - residual["start_time"], 0.0, None)
    ax.plot(t, 0.5 * expected.acceleration * tau**2, "--", label="Hoek & Bray: ½ g sin ψᵢ (1 − FS) t², FS 0.8")
    ax.set(xlabel="time (s)", ylabel="wedge's centroid along the line of intersection (m)")
    ax.legend(fontsize="small")
    plotting.mark_stages(ax, res)
    fig.savefig(FIGURES / "stages-wedge-history.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    tunnel(Path(sys.argv[1]))
    wedge(Path(sys.argv[2]))
