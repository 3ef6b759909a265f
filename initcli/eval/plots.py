"""Box plots like the paper's Fig. 9 (per site) and Fig. 12 (per method), and sweep curves."""

from __future__ import annotations

import io
from pathlib import Path

from bimkit.atomic import write_bytes_atomic
from initcli.eval.records import METHODS, MethodSummary, TrialRecord

__all__ = ["METHOD_COLOURS", "SITE_STYLES", "fig12", "fig9", "sweep_plot"]


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _save_png(fig, path: Path) -> None:
    """Render to memory, then write through a temporary file and a rename."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    write_bytes_atomic(path, buffer.getvalue())


def _box(ax, groups: list[list[float]], labels: list[str], ylabel: str, title: str) -> None:
    data = [g if g else [float("nan")] for g in groups]
    ax.boxplot(data, showmeans=True)
    ax.set_xticks(range(1, len(labels) + 1), labels, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.grid(axis="y", alpha=0.3)
    for i, g in enumerate(groups, start=1):
        ax.annotate(
            f"n={len(g)}",
            (i, 0),
            xycoords=("data", "axes fraction"),
            xytext=(0, 2),
            textcoords="offset points",
            ha="center",
            fontsize=7,
            color="0.4",
        )


def fig9(records: list[TrialRecord], path: Path) -> None:
    """Fig. 9: features, distances (coarse / total), translational and rotational errors of the
    BIM method after rectification and after fine tuning, one box per site; successful trials."""
    plt = _pyplot()
    rows = [r for r in records if not r.sweep_key and r.success]
    sites = list(dict.fromkeys(r.site for r in records if not r.sweep_key))
    fig, axes = plt.subplots(1, 4, figsize=(16, 4))

    def values(method: str, attr: str) -> list[list[float]]:
        return [
            [
                getattr(r, attr)
                for r in rows
                if r.site == s and r.method == method and getattr(r, attr) is not None
            ]
            for s in sites
        ]

    _box(axes[0], values("bim", "features"), sites, "features", "(a) detected features (coarse)")
    labels = [f"{s}\n{kind}" for s in sites for kind in ("coarse", "total")]
    coarse, total = values("bim", "distance_m"), values("bim+pf", "distance_m")
    _box(
        axes[1],
        [g for pair in zip(coarse, total, strict=True) for g in pair],
        labels,
        "m",
        "(b) moving distance",
    )
    labels = [f"{s}\n{kind}" for s in sites for kind in ("rect.", "PF")]
    for ax, attr, unit, title in (
        (axes[2], "error_translation_m", "m", "(c, d) translational error"),
        (axes[3], "error_rotation_deg", "degrees", "(e, f) rotational error"),
    ):
        rect, fine = values("bim", attr), values("bim+pf", attr)
        _box(ax, [g for pair in zip(rect, fine, strict=True) for g in pair], labels, unit, title)
    fig.suptitle("BIM-based initialisation per site (cf. paper Fig. 9), successful trials")
    _save_png(fig, path)
    plt.close(fig)


def fig12(records: list[TrialRecord], site: str, path: Path) -> None:
    """Fig. 12: moving distance, translational and rotational error of every method on one site."""
    plt = _pyplot()
    rows = [r for r in records if not r.sweep_key and r.site == site]
    methods = [m for m in METHODS if any(r.method == m for r in rows)]
    fig, axes = plt.subplots(1, 3, figsize=(14, 4))
    labels = []
    for m in methods:
        ok = [r for r in rows if r.method == m]
        rate = 100.0 * sum(r.success for r in ok) / max(len(ok), 1)
        labels.append(f"{m}\n{rate:.0f}% ok")
    for ax, attr, unit, title in (
        (axes[0], "distance_m", "m", "(a) moving distance"),
        (axes[1], "error_translation_m", "m", "(b) translational error"),
        (axes[2], "error_rotation_deg", "degrees", "(c) rotational error"),
    ):
        groups = [
            [getattr(r, attr) for r in rows if r.method == m and r.success and getattr(r, attr) is not None]
            for m in methods
        ]
        _box(ax, groups, labels, unit, title)
    fig.suptitle(f"{site}: methods compared (cf. paper Fig. 12), successful trials")
    _save_png(fig, path)
    plt.close(fig)


METHOD_COLOURS = {"bim": "tab:blue", "bim+pf": "tab:green", "amcl": "tab:red", "markers": "tab:purple"}
SITE_STYLES = ("-", "--", ":", "-.")


def sweep_plot(summaries: list[MethodSummary], key: str, path: Path) -> None:
    """Success rate and mean translational error against the swept value: one colour per method,
    one line style per site."""
    plt = _pyplot()
    rows = [s for s in summaries if s.sweep_key == key]
    sites = list(dict.fromkeys(s.site for s in rows))
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.5))
    for site, method in dict.fromkeys((s.site, s.method) for s in rows):
        line = sorted((float(s.sweep_value), s) for s in rows if s.site == site and s.method == method)
        xs = [v for v, _ in line]
        style = {
            "color": METHOD_COLOURS.get(method, "0.3"),
            "linestyle": SITE_STYLES[sites.index(site) % len(SITE_STYLES)],
            "marker": "o",
            "label": f"{method} · {site}",
        }
        axes[0].plot(xs, [s.success_rate for _, s in line], **style)
        errors = [
            s.error_translation_mean_m if s.error_translation_mean_m is not None else float("nan")
            for _, s in line
        ]
        axes[1].plot(xs, errors, **style)
    axes[0].set_ylabel("success rate (%)")
    axes[0].set_ylim(-5, 105)
    axes[1].set_ylabel("mean translational error of successes (m)")
    axes[1].set_yscale("log")
    for ax in axes:
        ax.set_xlabel(key)
        ax.grid(alpha=0.3, which="both")
    axes[1].legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    fig.suptitle(f"Robustness sweep: {key} (colour: method, line style: site)")
    _save_png(fig, path)
    plt.close(fig)
