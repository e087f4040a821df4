"""The benchmarks' one figure: run time against error on log axes, with the target's
time and error as dotted lines (the corner a stage must reach)."""

from __future__ import annotations

from pathlib import Path

#: Errors are drawn no lower than this (an exact result would leave the log axis).
FLOOR = 1e-16


def time_error_plot(path: Path, series, target: tuple[float, float], *, xlabel: str,
                    ylabel: str, title: str, floor: float = FLOOR,
                    size: tuple[float, float] = (6.5, 4.5)) -> None:
    """Write ``path``: ``series`` is [(label, times, errors, style)], ``target`` (time,
    error)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=size)
    for label, times, errors, style in series:
        ax.loglog(list(times), [max(e, floor) for e in errors], style, label=label)
    ax.axvline(target[0], color="grey", ls=":")
    ax.axhline(target[1], color="grey", ls=":")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
