#!/usr/bin/env python3
"""Plots of an atmosphere for people: solar spectrum, extinction, transmittance,
sky luminance and the convergence of the scattering orders (docs/plots.md).

The numbers come from the library through `atmos plot-data`, which writes CSV
files; this script only draws them with matplotlib (Debian: python3-matplotlib,
installed by scripts/setup.sh).

    python3 scripts/plots.py --atmos build/apps/atmos --out docs/plots -- --planet earth --wavelengths 15
    python3 scripts/plots.py --csv DIR --out DIR2    # draw CSV files written before

Arguments after `--` go to `atmos plot-data` (--planet, --wavelengths,
--orders, --density-scale, --solar, --tables, --cache-dir, ...).
"""

import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile

PLOTS = ("solar", "extinction", "transmittance", "sky", "convergence")


def import_matplotlib():
    """matplotlib's pyplot with the file-only backend. If this interpreter has
    no matplotlib (e.g. a pyenv or venv python3 ahead of Debian's on PATH),
    run the script again with Debian's /usr/bin/python3, which has it once
    python3-matplotlib is installed."""
    try:
        import matplotlib
    except ImportError:
        system = "/usr/bin/python3"
        if os.path.exists(system) and os.path.realpath(sys.executable) != os.path.realpath(system) \
                and not os.environ.get("ATMOS_PLOTS_REEXEC"):
            os.environ["ATMOS_PLOTS_REEXEC"] = "1"
            os.execv(system, [system] + sys.argv)
        sys.exit("plots.py: error: matplotlib is not installed (Debian: apt-get install python3-matplotlib, "
                 "or run scripts/setup.sh)")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return matplotlib, plt


def read_csv(path):
    """Header and rows of a CSV file; cells are floats where they parse."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise SystemExit(f"plots.py: error: {path} is empty")
    header, body = rows[0], rows[1:]

    def cell(text):
        try:
            return float(text)
        except ValueError:
            return text

    return header, [[cell(c) for c in row] for row in body if row]


def column(header, rows, name):
    i = header.index(name)
    return [row[i] for row in rows]


def read_info(directory):
    path = os.path.join(directory, "info.csv")
    if not os.path.exists(path):
        return {}
    _, rows = read_csv(path)
    return {str(row[0]): row[1] for row in rows if len(row) >= 2}


def describe(info):
    """Subtitle: planet, mode and orders."""
    planet = str(info.get("planet", "?"))
    wavelengths = str(info.get("wavelengths_nm", "")).split()
    mode = f"spectral, {len(wavelengths)} wavelengths" if len(wavelengths) > 3 else \
        "3 wavelengths (" + ", ".join(wavelengths) + " nm)"
    parts = [planet.capitalize(), mode]
    orders = info.get("orders")
    if orders not in (None, ""):
        parts.append(f"{int(orders)} orders")
    scale = info.get("density_scale")
    if isinstance(scale, float) and scale != 1.0:
        parts.append(f"density x{scale:g}")
    solar = info.get("solar")
    if solar not in (None, "", "planet file"):
        parts.append(f"sun: {solar}")
    return ", ".join(parts)


def working_wavelengths(info):
    return [float(w) for w in str(info.get("wavelengths_nm", "")).split()]


def wavelength_colour(nm):
    """An approximate display colour of a wavelength (for legends only)."""
    if nm < 440:
        r, g, b = -(nm - 440) / 80, 0.0, 1.0
    elif nm < 490:
        r, g, b = 0.0, (nm - 440) / 50, 1.0
    elif nm < 510:
        r, g, b = 0.0, 1.0, -(nm - 510) / 20
    elif nm < 580:
        r, g, b = (nm - 510) / 70, 1.0, 0.0
    elif nm < 645:
        r, g, b = 1.0, -(nm - 645) / 65, 0.0
    else:
        r, g, b = 1.0, 0.0, 0.0
    fade = 0.4 + 0.6 * (nm - 360) / 60 if nm < 420 else 0.4 + 0.6 * (830 - nm) / 130 if nm > 700 else 1.0
    return tuple(max(0.0, min(1.0, c * fade)) * 0.85 for c in (r, g, b))


def mark_wavelengths(ax, info):
    """Thin ticks at the working wavelengths along the bottom of a spectral plot."""
    wl = working_wavelengths(info)
    for i, w in enumerate(wl):
        ax.axvline(w, color="0.6", lw=0.6, ls=":", zorder=0, label="working wavelengths" if i == 0 else None)


def finish(fig, ax_or_axes, out, name, title, info):
    fig.suptitle(title, fontsize=13, y=0.995)
    axes = ax_or_axes if isinstance(ax_or_axes, (list, tuple)) else [ax_or_axes]
    axes[0].set_title(describe(info), fontsize=9, color="0.35", loc="left")
    for ax in axes:
        ax.grid(True, which="major", alpha=0.3)
    fig.tight_layout()
    path = os.path.join(out, name + ".png")
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def plot_solar(plt, data, out, info):
    header, rows = read_csv(os.path.join(data, "solar.csv"))
    fig, ax = plt.subplots(figsize=(8, 4.5))
    ax.plot(column(header, rows, "wavelength_nm"), column(header, rows, "irradiance_W_m2_nm"), color="#d98c00",
            lw=1.2, label="solar irradiance (top of the atmosphere)")
    mark_wavelengths(ax, info)
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("spectral irradiance (W m$^{-2}$ nm$^{-1}$)")
    ax.set_xlim(360, 830)
    ax.set_ylim(bottom=0)
    ax.legend(loc="lower right")
    finish(fig, ax, out, "solar", "Solar spectrum at the top of the atmosphere, normal incidence", info)


def plot_extinction(plt, data, out, info):
    header, rows = read_csv(os.path.join(data, "extinction.csv"))
    wl = column(header, rows, "wavelength_nm")
    fig, ax = plt.subplots(figsize=(8, 5))
    names = []
    for h in header:
        m = re.fullmatch(r"scattering_(.+)_per_m", h)
        if m:
            names.append(m.group(1))
    cycle = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    lowest = math.inf
    for i, name in enumerate(names):
        colour = cycle[i % len(cycle)]
        for kind, style in (("scattering", "-"), ("absorption", "--")):
            values = column(header, rows, f"{kind}_{name}_per_m")
            if max(values) <= 0.0:
                continue  # nothing to draw on a log axis
            lowest = min(lowest, min(v for v in values if v > 0.0))
            ax.plot(wl, [v if v > 0.0 else math.nan for v in values], style, color=colour, lw=1.6,
                    label=f"{name} {kind}")
    mark_wavelengths(ax, info)
    ax.set_yscale("log")
    ax.set_xlim(360, 830)
    ax.set_xlabel("wavelength (nm)")
    ax.set_ylabel("coefficient at reference density (m$^{-1}$)")
    ax.legend(fontsize=9, loc="best")
    finish(fig, ax, out, "extinction", "Scattering (solid) and absorption (dashed) per constituent", info)


def plot_transmittance(plt, data, out, info):
    header, rows = read_csv(os.path.join(data, "transmittance.csv"))
    altitudes = sorted(set(column(header, rows, "altitude_km")))
    fig, (left, middle, right) = plt.subplots(1, 3, figsize=(15, 4.8))
    # Left and middle: sunlight-weighted luminance against the angle, the
    # middle one near the horizon on a log scale.
    palette = plt.get_cmap("cividis")
    for i, altitude in enumerate(altitudes):
        sel = [r for r in rows if r[0] == altitude]
        zen = column(header, sel, "view_zenith_deg")
        lum = column(header, sel, "luminance")
        colour = palette(0.85 * i / max(1, len(altitudes) - 1))
        left.plot(zen, lum, color=colour, lw=1.8, label=f"{altitude:g} km")
        middle.semilogy(zen, lum, color=colour, lw=1.8, label=f"{altitude:g} km")
    for ax in (left, middle):
        ax.axvline(90, color="0.5", lw=0.8, ls="--")
        ax.set_xlabel("view zenith angle (deg); 90 = horizontal")
        ax.legend(fontsize=8, loc="lower left", title="observer altitude", title_fontsize=8)
    left.set_xlim(0, 95)
    left.set_ylim(0, 1.02)
    left.set_ylabel("transmittance to the top (luminance)")
    middle.set_xlim(75, 95)
    middle.set_ylabel("transmittance to the top (luminance, log)")
    middle.set_title("near the horizon: a curve ends where rays hit the ground", fontsize=9, color="0.35", loc="left")

    # Right: the spectrum of the transmittance from the lowest altitude at a few angles.
    wl_columns = [(float(m.group(1)), h) for h in header for m in [re.fullmatch(r"transmittance_(.+)nm", h)] if m]
    ground = [r for r in rows if r[0] == altitudes[0]]
    zen = column(header, ground, "view_zenith_deg")
    shown = [z for z in (0, 60, 75, 85, 88, 90) if z in zen]
    colours = plt.get_cmap("viridis")
    for j, z in enumerate(shown):
        row = ground[zen.index(z)]
        right.semilogy([w for w, _ in wl_columns], [row[header.index(h)] for _, h in wl_columns], "o-", ms=3,
                       color=colours(0.9 * j / max(1, len(shown) - 1)), label=f"zenith {z:g}°")
    right.set_xlim(350, 840)
    right.set_xlabel("wavelength (nm)")
    right.set_ylabel(f"transmittance from {altitudes[0]:g} km (log)")
    right.set_title("at each working wavelength", fontsize=9, color="0.35", loc="left")
    right.legend(fontsize=8, loc="lower right")
    finish(fig, [left, middle, right], out, "transmittance",
           "Transmittance to the top of the atmosphere (luminance: of sunlight, sRGB-weighted)", info)


def plot_sky(plt, data, out, info):
    header, rows = read_csv(os.path.join(data, "sky.csv"))
    elevations = sorted(set(column(header, rows, "sun_elevation_deg")))
    fig, ax = plt.subplots(figsize=(9, 5))
    colours = plt.get_cmap("plasma")
    for i, elevation in enumerate(elevations):
        sel = [r for r in rows if r[0] == elevation]
        # Signed angle: towards the sun positive, away from it negative.
        points = sorted((r[2] if r[1] == 0.0 else -r[2], r[header.index("luminance_cd_m2")]) for r in sel)
        colour = colours(0.1 + 0.75 * i / max(1, len(elevations) - 1))
        ax.plot([p[0] for p in points], [p[1] for p in points], color=colour, lw=1.8,
                label=f"sun elevation {elevation:g}°")
        ax.axvline(90.0 - elevation, color=colour, lw=0.8, ls=":")
    ax.plot([], [], color="0.4", lw=0.8, ls=":", label="sun direction")
    ax.set_yscale("log")
    ax.set_xlim(-90, 90)
    ax.set_xticks(range(-90, 91, 15))
    ax.set_xticklabels(["-90\nhorizon" if t == -90 else "0\nzenith" if t == 0 else "90\nhorizon" if t == 90
                        else str(t) for t in range(-90, 91, 15)])
    ax.set_xlabel("view zenith angle in the sun's vertical plane (deg): < 0 away from the sun, > 0 towards it")
    ax.set_ylabel("sky luminance (cd m$^{-2}$)")
    ax.legend(fontsize=9, loc="best")
    finish(fig, ax, out, "sky", "Sky luminance seen from the ground (without the sun disc)", info)


def plot_convergence(plt, data, out, info):
    header, rows = read_csv(os.path.join(data, "convergence.csv"))
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
    if not rows:
        for ax in (left, right):
            ax.text(0.5, 0.5, "one scattering order only:\nnothing to compare", ha="center", va="center",
                    transform=ax.transAxes)
    else:
        # The last row may be the tail (tail = 1): all orders from `order` on,
        # solved at once (auto orders that hit the cap), not one more order.
        tails = column(header, rows, "tail") if "tail" in header else [0] * len(rows)
        single = [r for r, t in zip(rows, tails) if not t]
        tail = [r for r, t in zip(rows, tails) if t]
        orders = column(header, single, "order")
        added = column(header, single, "added")
        relative = column(header, single, "relative")
        left.semilogy(orders, added, "o-", color="#1f77b4", label="added by order n")
        right.semilogy(orders, relative, "o-", color="#d62728", label="added / orders 1..n")
        if tail:
            first = column(header, tail, "order")
            left.semilogy(first, column(header, tail, "added"), "s", color="#2ca02c",
                          label=f"orders {int(first[0])}+ (solved at once)")
            right.semilogy(first, column(header, tail, "relative"), "s", color="#2ca02c",
                           label=f"orders {int(first[0])}+ / all the light")
        right.axhline(1e-3, color="0.4", ls="--", lw=0.9, label="--orders auto tolerance (0.1 %)")
        ticks = orders + (column(header, tail, "order") if tail else [])
        for ax in (left, right):
            ax.set_xticks(ticks if len(ticks) <= 20 else ticks[::max(1, len(ticks) // 10)])
            ax.grid(True, which="minor", alpha=0.12)
            ax.legend(fontsize=9, loc="upper right")
    unit = "cd m$^{-2}$" if str(info.get("mode")) == "spectral" else "radiance units"
    left.set_xlabel("scattering order n")
    left.set_ylabel(f"luminance added, summed over the table ({unit})")
    right.set_xlabel("scattering order n")
    right.set_ylabel("relative contribution")
    finish(fig, [left, right], out, "convergence", "Convergence of the scattering orders", info)


def main():
    argv = sys.argv[1:]
    passthrough = []
    if "--" in argv:
        cut = argv.index("--")
        argv, passthrough = argv[:cut], argv[cut + 1:]
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     epilog="Arguments after -- are passed to `atmos plot-data`.")
    parser.add_argument("--atmos", default=None, help="the atmos binary (default: build/apps/atmos of this checkout)")
    parser.add_argument("--out", required=True, help="directory for the PNG files (created if missing)")
    parser.add_argument("--csv", default=None,
                        help="directory for the CSV files (kept); with --no-run, where to read them from")
    parser.add_argument("--no-run", action="store_true", help="do not run atmos: draw the CSV files in --csv")
    parser.add_argument("--only", default=",".join(PLOTS), help="comma-separated subset of " + ", ".join(PLOTS))
    args = parser.parse_args(argv)
    only = [p.strip() for p in args.only.split(",") if p.strip()]
    for p in only:
        if p not in PLOTS:
            parser.error(f"--only: unknown plot {p!r} (expected {', '.join(PLOTS)})")
    if args.no_run and not args.csv:
        parser.error("--no-run needs --csv DIR")

    matplotlib, plt = import_matplotlib()
    plt.rcParams.update({"font.size": 10, "axes.titlesize": 10, "legend.framealpha": 0.9})

    with tempfile.TemporaryDirectory(prefix="atmos-plots-") as scratch:
        data = args.csv or scratch
        if not args.no_run:
            atmos = args.atmos or os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "build", "apps", "atmos")
            command = [atmos, "plot-data", "--out", data] + passthrough
            print("running " + " ".join(command), flush=True)
            try:
                result = subprocess.run(command, stdout=subprocess.DEVNULL)
            except OSError as e:
                sys.exit(f"plots.py: error: cannot run {atmos}: {e.strerror} (build it, or pass --atmos)")
            if result.returncode != 0:
                sys.exit(result.returncode)
        os.makedirs(args.out, exist_ok=True)
        info = read_info(data)
        for name in only:
            globals()["plot_" + name](plt, data, args.out, info)
            plt.close("all")


if __name__ == "__main__":
    main()
