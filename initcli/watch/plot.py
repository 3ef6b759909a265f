"""``bim-init watch --plot``: the localiser's track on the storey's map with the events, and the
checks over travel (the fit, the beams through walls, the CUSUM against its threshold)."""

from __future__ import annotations

import io
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from bimkit.atomic import write_bytes_atomic  # noqa: E402
from bimtools.site.load import Site  # noqa: E402
from initcli.core.watch.params import WatchParams  # noqa: E402
from initcli.watch.records import EventKind  # noqa: E402
from initcli.watch.replay import WatchResult  # noqa: E402

__all__ = ["plot_watch"]

COLOURS = {EventKind.LOST: "tab:red", EventKind.RECOVERED: "tab:green", EventKind.SUSPECT: "tab:orange"}


def plot_watch(
    result: WatchResult, site: Site, out_path: Path | str, params: WatchParams | None = None
) -> Path:
    """Draw ``result`` on its storey's map and save it (PNG, PDF or SVG by the suffix), atomically."""
    out_path = Path(out_path)
    threshold = (params or WatchParams()).threshold
    fig, (plan, over) = plt.subplots(2, 1, figsize=(10, 11), gridspec_kw={"height_ratios": [3, 1.3]})
    grid = site.storeys[result.storey].grid
    if grid is not None:
        rows, cols = grid.cells.shape
        x0, y0 = grid.origin[0], grid.origin[1]
        extent = (x0, x0 + cols * grid.resolution, y0, y0 + rows * grid.resolution)
        plan.imshow(grid.cells, cmap="gray", extent=extent, interpolation="nearest", vmin=0, vmax=255)
    if result.localiser:
        track = np.array([[p.x, p.y] for _, p in result.localiser])
        plan.plot(
            track[:, 0], track[:, 1], "-", color="tab:blue", lw=1.2, label="localiser's track (recorded)"
        )
    lost = [c for c in result.checks if c.state == "lost"]
    if lost:
        pts = np.array([[c.localiser.x, c.localiser.y] for c in lost])
        plan.plot(pts[:, 0], pts[:, 1], ".", color="tab:red", ms=3, label="checked while lost")
    for e in result.events:
        near = min(result.checks, key=lambda c: abs(c.t - e.t), default=None)
        if e.kind is EventKind.RECOVERED and e.pose is not None:
            plan.arrow(
                e.pose.x,
                e.pose.y,
                0.8 * math.cos(e.pose.yaw),
                0.8 * math.sin(e.pose.yaw),
                width=0.08,
                color=COLOURS[e.kind],
                length_includes_head=True,
            )
            plan.plot([e.pose.x], [e.pose.y], "o", color=COLOURS[e.kind], label=f"recovered at {e.t:.1f} s")
        elif near is not None and e.kind is EventKind.LOST:
            plan.plot(
                [near.localiser.x],
                [near.localiser.y],
                "X",
                ms=10,
                color=COLOURS[e.kind],
                label=f"lost at {e.t:.1f} s",
            )
    plan.set_aspect("equal")
    plan.set_xlabel("x [m]")
    plan.set_ylabel("y [m]")
    plan.set_title(f"bim-init watch, storey {result.storey}: {result.summary()}", fontsize=9)
    plan.legend(loc="best", fontsize=8)
    if result.checks:
        travel = np.array([c.travel for c in result.checks])
        over.plot(travel, [c.fit for c in result.checks], color="tab:blue", lw=1, label="fit on walls")
        over.plot(
            travel, [c.through for c in result.checks], color="tab:purple", lw=1, label="beams through walls"
        )
        over.plot(travel, [c.statistic for c in result.checks], color="black", lw=1.5, label="CUSUM")
        over.axhline(threshold, color="black", ls=":", lw=1, label="threshold")
    for e in result.events:
        over.axvline(e.travel, color=COLOURS[e.kind], lw=1.5, ls="--")
    over.set_xlabel("odometry travel [m]")
    over.set_ylabel("share / evidence")
    over.legend(loc="upper left", fontsize=8, ncol=4)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, dpi=110, format=out_path.suffix.lower().lstrip(".") or "png")
    plt.close(fig)
    write_bytes_atomic(out_path, buffer.getvalue())
    return out_path
