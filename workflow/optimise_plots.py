"""Pictures and the report section of an optimisation (see :mod:`.optimise_results`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .optimise_spec import OptimiseSpec

#: Most variables drawn under the front (one panel each).
MAX_VARIABLE_PANELS = 6


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _label(name: str) -> str:
    return name.partition(".")[2] or name


def _front_of(spec: OptimiseSpec, rows: list[dict]) -> list[dict]:
    from .optimise_results import pareto_rows

    return pareto_rows(spec, rows)


def plot_front(path: Path, spec: OptimiseSpec, rows: list[dict], front: list[dict]) -> None:
    """The front of the first two objectives over every feasible design, and under it
    the variables of each front design against the first objective (seed 000 Fig. 14)."""
    from .optimise_results import feasible_F

    plt = _pyplot()
    x_name, y_name = spec.objectives[0].name, spec.objectives[1].name
    panels = [v for v in spec.variables][:MAX_VARIABLE_PANELS]
    fig, axes = plt.subplots(1 + len(panels), 1, sharex=True,
                             figsize=(6.0, 3.2 + 1.6 * len(panels)),
                             gridspec_kw={"height_ratios": [2.0] + [1.0] * len(panels)})
    axes = np.atleast_1d(axes)
    _, ok = feasible_F(spec, rows)
    axes[0].plot([rows[i][x_name] for i in ok], [rows[i][y_name] for i in ok], ".",
                 color="0.75", ms=3, label=f"feasible designs ({len(ok)})")
    fx = [r[x_name] for r in front]
    axes[0].plot(fx, [r[y_name] for r in front], "o-", color="tab:red", ms=4,
                 label=f"Pareto front ({len(front)})")
    axes[0].set_ylabel(_label(y_name))
    axes[0].legend(fontsize=8)
    axes[0].grid(alpha=0.3)
    for ax, v in zip(axes[1:], panels, strict=False):
        values = [r[v.name] for r in front]
        if v.kind == "choice":
            values = [v.choices.index(x) for x in values]
            ax.set_yticks(range(len(v.choices)), [str(c) for c in v.choices])
        ax.plot(fx, values, "o", color="tab:red", ms=4)
        ax.set_ylabel(_label(v.name))
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(_label(x_name))
    fig.suptitle(f"{spec.name}: {spec.objectives[0].sense} {_label(x_name)}, "
                 f"{spec.objectives[1].sense} {_label(y_name)}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_fronts_by(path: Path, spec: OptimiseSpec, rows: list[dict], var) -> None:
    """One front per value of a discrete variable (seed 000 Fig. 15: N1 = 3 to 6)."""
    plt = _pyplot()
    x_name, y_name = spec.objectives[0].name, spec.objectives[1].name
    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    values = var.choices if var.kind == "choice" else range(var.low, var.high + 1)
    for value in values:
        front = _front_of(spec, [r for r in rows if r.get(var.name) == value])
        if front:
            ax.plot([r[x_name] for r in front], [r[y_name] for r in front], "o-", ms=3,
                    label=f"{_label(var.name)} = {value} ({len(front)})")
    ax.set_xlabel(_label(x_name))
    ax.set_ylabel(_label(y_name))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"{spec.name}: fronts by {_label(var.name)} (designs of this run)",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_hypervolume(path: Path, hv: list[dict]) -> None:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.0, 3.2))
    ax.plot([h["generation"] + 1 for h in hv], [h["hypervolume"] for h in hv], "o-", ms=3)
    ax.set_xlabel("generation")
    ax.set_ylabel("hypervolume")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_all(folder: Path, spec: OptimiseSpec, rows: list[dict], front: list[dict],
             hv: list[dict]) -> list[tuple[str, str]]:
    """Every picture, as (file name, caption)."""
    out = []
    if len(spec.objectives) >= 2 and front:
        plot_front(folder / "front.png", spec, rows, front)
        out.append(("front.png", "Pareto front of the first two objectives over every "
                                 "feasible design, and the variables of its designs"))
        for v in spec.variables:
            if v.kind in ("int", "choice"):
                name = f"front_by_{_label(v.name)}.png"
                plot_fronts_by(folder / name, spec, rows, v)
                out.append((name, f"one front per value of {v.name}"))
    if hv:
        plot_hypervolume(folder / "hypervolume.png", hv)
        out.append(("hypervolume.png", "hypervolume of the feasible designs found up to "
                                       "each generation"))
    return out


def write_page(folder: Path, spec: OptimiseSpec, front: list[dict], hv: list[dict],
               record: dict, pictures: list[tuple[str, str]]) -> Path:
    """``index.html``: the run, its pictures and its Pareto set."""
    from rotorflow.postprocess.report import esc, figure, page, table

    names = [v.name for v in spec.variables] + spec.figures
    objectives = ", ".join(f"{o.sense} {esc(o.name)}" for o in spec.objectives)
    body = [f"<h1>rotorflow optimise: {esc(spec.name)}</h1>",
            f"<p>NSGA-II (pymoo), seed {spec.seed}, population {spec.population}, "
            f"{record['generations']} generations: {objectives}. {record['evaluations']} "
            f"designs asked, {record['computed']} computed, {record['cached']} from the "
            f"store, {record['failed']} failed; {record['seconds']} s "
            f"({esc(record['where'])}).</p>"]
    if spec.constraints:
        body.append("<p>Constraints: " + ", ".join(
            esc(f"{c.name} {'>= ' + str(c.low) if c.low is not None else ''}"
                f"{' and ' if c.low is not None and c.high is not None else ''}"
                f"{'<= ' + str(c.high) if c.high is not None else ''}")
            for c in spec.constraints) + ".</p>")
    body += [figure(name, caption) for name, caption in pictures]
    body.append(f"<h2>Pareto set ({len(front)} designs)</h2>")
    body.append(table(names, [[r.get(n) for n in names] for r in front]))
    body.append("<p>Every design is in <code>points.csv</code>, the front in "
                "<code>pareto.csv</code>, the hypervolume in <code>hypervolume.csv</code>.</p>")
    path = Path(folder) / "index.html"
    path.write_text(page(f"rotorflow optimise: {spec.name}", "\n".join(body)))
    return path
