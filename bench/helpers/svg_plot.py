"""Line charts written as SVG by hand (no matplotlib on the benchmark machines).

`figure` lays panels out in a grid; each panel is a dict:

    {"title": str, "xlabel": str, "xs": [x axis: first and last = its range; the ticks
     unless "xticks" is given],
     "series": [{"name", "xs", "ys", "colour", "err" (optional ± bars)}],
     "logx": bool (log2 axis), "logy": bool (log10 axis, 1-2-5 ticks)}

A linear y axis starts at 0 and ends 15 % above the largest value.
`svg_plot` is the visibility benchmark's figure (bench/visibility_benchmark.py).
"""

import math
import os

PANEL_W, PANEL_H, PAD, TOP = 320, 220, 50, 40   # plot area, left margin, title band
COLUMN_STEP, ROW_STEP = 380, 300                 # one panel's cell in the grid


def tick_label(v):
    return str(int(v)) if float(v).is_integer() and abs(v) < 1e9 else f"{v:g}"


def log_ticks(lo, hi):
    """1-2-5 values between lo and hi (both > 0)."""
    out = []
    for decade in range(math.floor(math.log10(lo)) - 1, math.ceil(math.log10(hi)) + 1):
        for m in (1, 2, 5):
            v = m * 10.0 ** decade
            if lo <= v <= hi:
                out.append(float(f"{v:.6g}"))
    return out


def _y_axis(panel):
    values = [v for s in panel["series"] for v, e in zip(s["ys"], s.get("err") or [0] * len(s["ys"]))
              for v in (v + e, v)]
    if not panel.get("logy"):
        ymax = max(values) * 1.15 if values else 1
        return (lambda v: v / ymax), [ymax * k / 4 for k in range(5)], (lambda v: f"{v:.3f}")
    positive = [v for v in values if v > 0] or [1.0]
    lo, hi = math.log10(min(positive) / 1.3), math.log10(max(positive) * 1.3)
    ticks = log_ticks(10 ** lo, 10 ** hi)
    return (lambda v: (math.log10(max(v, 10 ** lo)) - lo) / (hi - lo)), ticks, (lambda v: f"{v:g}")


def _panel(parts, x0, y0, panel):
    w, h, xs = PANEL_W, PANEL_H, panel["xs"]
    logx = panel.get("logx", False)

    def X(v):
        if logx:
            return x0 + PAD + w * (math.log2(v) - math.log2(xs[0])) / max(math.log2(xs[-1]) - math.log2(xs[0]), 1e-9)
        return x0 + PAD + w * (v - xs[0]) / max(xs[-1] - xs[0], 1e-9)

    fraction, yticks, ylabel = _y_axis(panel)

    def Y(v):
        return y0 + h - h * fraction(v)

    parts.append(f'<text x="{x0 + PAD}" y="{y0 - 15}" font-size="13">{panel["title"]}</text>')
    parts.append(f'<line x1="{x0 + PAD}" y1="{y0 + h}" x2="{x0 + PAD + w}" y2="{y0 + h}" stroke="black"/>')
    parts.append(f'<line x1="{x0 + PAD}" y1="{y0}" x2="{x0 + PAD}" y2="{y0 + h}" stroke="black"/>')
    for v in panel.get("xticks", xs):
        parts.append(f'<text x="{X(v):.1f}" y="{y0 + h + 14}" text-anchor="middle">{tick_label(v)}</text>')
    for v in yticks:
        parts.append(f'<text x="{x0 + PAD - 4}" y="{Y(v) + 4:.1f}" text-anchor="end">{ylabel(v)}</text>')
    parts.append(f'<text x="{x0 + PAD + w / 2}" y="{y0 + h + 30}" text-anchor="middle">{panel["xlabel"]}</text>')
    for i, s in enumerate(panel["series"]):
        colour = s["colour"]
        pts = " ".join(f"{X(x):.1f},{Y(v):.1f}" for x, v in zip(s["xs"], s["ys"]))
        parts.append(f'<polyline points="{pts}" fill="none" stroke="{colour}" stroke-width="2"/>')
        for x, v, e in zip(s["xs"], s["ys"], s.get("err") or [None] * len(s["ys"])):
            if e:
                parts.append(f'<line x1="{X(x):.1f}" y1="{Y(v - e):.1f}" x2="{X(x):.1f}" y2="{Y(v + e):.1f}" '
                             f'stroke="{colour}"/>')
            parts.append(f'<circle cx="{X(x):.1f}" cy="{Y(v):.1f}" r="3" fill="{colour}"/>')
        parts.append(f'<text x="{x0 + PAD + w - 5}" y="{y0 + 14 + 14 * i}" text-anchor="end" fill="{colour}">'
                     f'{s["name"]}</text>')


def figure(panels, path, columns=2, caption=None):
    """Writes the panels, `columns` per row, to `path` (atomically)."""
    rows = max(1, math.ceil(len(panels) / columns))
    top = 20 if caption else 0
    width, height = COLUMN_STEP * columns, ROW_STEP * rows + 20 + top
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" '
             'font-size="11">', '<rect width="100%" height="100%" fill="white"/>']
    if caption:
        parts.append(f'<text x="10" y="16" font-size="13">{caption}</text>')
    for k, panel in enumerate(panels):
        _panel(parts, COLUMN_STEP * (k % columns), top + TOP + ROW_STEP * (k // columns), panel)
    parts.append("</svg>")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(parts))
    os.replace(path + ".tmp", path)


def svg_plot(results, path):
    """Visibility benchmark: unseen-pose AO error vs rays (lobes 2), and per-lobe errors (256 rays)."""
    def series(rows):
        xs = [r["rays"] if rows is rays_rows else r["lobes"] for r in rows]
        return [{"name": name, "xs": xs, "ys": [r[key] for r in rows], "colour": colour}
                for name, key, colour in (("ZH fit", "zh_fit_sh_rms", "#2a7"),
                                          ("model, training", "training_sh_rms", "#27c"),
                                          ("model, unseen poses", "unseen_sh_rms", "#c33"))]

    rays_rows = [r for r in results["sweep"] if r["lobes"] == 2]
    lobe_rows = [r for r in results["sweep"] if r["rays"] == results["lobe_rays"]]
    figure([{"title": "Lobes 2: error vs rays (SH RMS)", "xs": [r["rays"] for r in rays_rows],
             "series": series(rays_rows), "xlabel": "rays per vertex", "logx": True},
            {"title": f"Rays {results['lobe_rays']}: error vs lobes (SH RMS)", "xs": [r["lobes"] for r in lobe_rows],
             "series": series(lobe_rows), "xlabel": "lobes", "logx": False}], path)
