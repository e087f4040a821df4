"""The ``report`` stage: which sections a case's report shows, and in what order.

Each stage contributes its section through the ``report`` hook named in its
registration (:mod:`rotorflow.workflow.stages`); the stage collects the hooks of every
planned stage it reads, with each stage's stamp for the table of stages, and hands
them to :func:`rotorflow.postprocess.report.case_page`.  CFD stages add their
comparison tables and plots the same way, and appear in the report of every case that
planned them.
"""

from __future__ import annotations

from pathlib import Path

from rotorflow.postprocess.report import case_page

from .cache import StageContext, read_stamp
from .runner import resolve
from .stages import REGISTRY


def run_report(ctx: StageContext) -> dict:
    """index.html and its pictures from the upstream artifacts."""
    out = ctx.out
    sections, status = [], []
    order = list(REGISTRY)
    for name in sorted(ctx.inputs, key=lambda n: (REGISTRY[n].report_rank, order.index(n))):
        folder, stage = ctx.inputs[name], REGISTRY[name]
        stamp = read_stamp(folder) or {}
        status.append([name, stage.description, stamp.get("key", "")[:12],
                       stamp.get("created", ""), stamp.get("seconds", "")])
        if stage.report:
            sec = resolve(stage.report)(folder, out, ctx.case)
            if sec is not None:
                sections.append((name, sec))
    case_path = Path(ctx.case_path)
    text = case_path.read_text() if case_path.is_file() else ""
    (out / "index.html").write_text(case_page(ctx.case.name, ctx.case_path, text, status,
                                              sections))
    images = sorted(p.name for p in out.glob("*.png"))
    return {"index": "index.html", "images": images, "sections": [n for n, _ in sections]}
