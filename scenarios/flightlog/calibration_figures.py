"""The figures of ``quadcosim calibrate``: the field residual against the current or the
throttle before and after the exported model, and the heading before and after over the flight."""

from __future__ import annotations

import numpy as np
from quadcosim.calibration.flight.evaluate import tilt_compensated_heading, wrap
from quadcosim.calibration.flight.linear import earth_and_offset

from quadcosim.infra.files import printable, save_figure

TESLA_TO_UT = 1e6


def _pyplot():
    from quadcosim.infra.files import headless_backend

    headless_backend()
    import matplotlib.pyplot as plt

    return plt


#: Bins of the regressor in which the residual's median and quartiles are drawn: equal counts of
#: samples (at most RESIDUAL_BINS bins, each of at least RESIDUAL_BIN_SAMPLES), so they reach
#: wherever the samples are; bins of equal width left the tails of a flight's current unbinned.
RESIDUAL_BINS, RESIDUAL_BIN_SAMPLES = 12, 20


def _binned(x: np.ndarray, y: np.ndarray):
    """The median of ``x`` in each bin of equal count (sorted by ``x``), and the 25th, 50th and 75th
    percentiles of ``y`` in each: (B,) and (B, 3); empty with fewer than RESIDUAL_BIN_SAMPLES samples."""
    order = np.argsort(x, kind="stable")
    count = min(RESIDUAL_BINS, len(x) // RESIDUAL_BIN_SAMPLES)
    bins = np.array_split(order, count) if count else []
    centres = [np.median(x[rows]) for rows in bins]
    quartiles = [np.percentile(y[rows], [25, 50, 75]) for rows in bins]
    return np.array(centres), np.array(quartiles).reshape(-1, 3)


def residual_figure(parts, fitted, name: str, path, title: str):
    """Residual field (uT, body axes) after the Earth field and offset alone, and after the model
    ``fitted`` (named ``name``), against its regressor, on the held-out ``parts``, into ``path``;
    ``title`` heads the figure. Each is drawn as its samples (faint) and, over them, its median
    and quartiles in bins of the regressor, so the two clouds stay apart where they overlap."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True, constrained_layout=True)
    x = np.concatenate([p.current() if name == "current" else p.throttle() for p in parts])
    before = np.concatenate([earth_and_offset(p.rotation, p.raw, p.earth).residual[0] for p in parts])
    after = np.concatenate([earth_and_offset(p.rotation, p.raw - fitted.predict(p), p.earth).residual[0]
                            for p in parts])
    styles = ((before, "0.35", "Earth field and offset only", "--"), (after, "C3", f"with the {name} model", "-"))
    for k, ax in enumerate(axes):
        for residual, colour, label, line in styles:
            y = -residual[:, k] * TESLA_TO_UT
            ax.plot(x, y, ".", ms=1.5, color=colour, alpha=0.12, rasterized=True)
            centres, q = _binned(x, y)
            ax.fill_between(centres, q[:, 0], q[:, 2], color=colour, alpha=0.25, lw=0)
            ax.plot(centres, q[:, 1], line, color=colour, lw=2, label=f"{label}: median, quartiles")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel("battery current (A)" if name == "current" else "collective throttle (1)")
        ax.set_title(f"body {'xyz'[k]}")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("field left unexplained (uT)")
    axes[0].legend(fontsize=8, loc="best")
    fig.suptitle(printable(title), fontsize=10)
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)


def heading_figure(data, fitted, name: str, cut: float, path, title: str):
    """Tilt-compensated heading error (deg) against the log's heading, the constant offset
    removed, without and with the model ``fitted`` (named ``name``), over the whole flight
    ``data`` (FlightData); the held-out part after ``cut`` (s) shaded; into ``path`` under ``title``."""
    plt = _pyplot()
    base = earth_and_offset(data.rotation, data.raw, data.earth)
    predicted = fitted.predict(data)
    fit = earth_and_offset(data.rotation, data.raw - predicted, data.earth)
    fig, ax = plt.subplots(figsize=(11, 4), constrained_layout=True)
    t0 = data.time[0]
    for field, label, colour in ((data.raw - base.nuisance[0, 3:], "Earth field and offset only", "0.5"),
                                 (data.raw - predicted - fit.nuisance[0, 3:], f"with the {name} model", "C3")):
        error = wrap(tilt_compensated_heading(data.body(field), data.euler) - data.euler[:, 2])
        error = wrap(error - np.angle(np.mean(np.exp(1j * error))))
        rms = np.degrees(np.sqrt(np.mean(error**2)))
        ax.plot(data.time - t0, np.degrees(error), lw=0.8, color=colour, label=f"{label} (RMS {rms:.2f} deg)")
    ax.axvspan(cut - t0, data.time[-1] - t0, color="C0", alpha=0.08, label="held out for testing")
    ax.set_xlabel("time from the first sample (s)")
    ax.set_ylabel("compass heading - log heading (deg)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.suptitle(printable(title), fontsize=10)
    try:
        save_figure(fig, path, dpi=110)
    finally:
        plt.close(fig)
