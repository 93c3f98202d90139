"""Published filters for comparison, run from their maintained packages (not rewritten).

``vqf``
    VQF (Laidig, Seel, "VQF: Highly accurate IMU orientation estimation with bias
    estimation and magnetic disturbance rejection", Information Fusion, 2023), from the
    ``vqf`` package: rest and motion bias estimation, magnetic disturbance rejection. Gains:
    any parameter of ``vqf.VQF`` by name (``tauAcc``, ``tauMag`` in s, ...), package defaults
    otherwise. VQF initialises itself from the first samples: ``q0`` and ``initial`` are not
    used.
``madgwick``
    Madgwick's gradient-descent filter (Madgwick, Harrison, Vaidyanathan, "Estimation of
    IMU and MARG orientation using a gradient descent algorithm", 2011), from the ``ahrs``
    package (``Madgwick.updateMARG``). Gain ``beta`` (rad/s). No bias estimate.
``mahony``
    Mahony's explicit complementary filter with bias (Mahony, Hamel, Pflimlin, "Nonlinear
    complementary filters on the special orthogonal group", 2008), from the ``ahrs`` package
    (``Mahony.updateMARG``): gains ``k_P`` (1/s) and ``k_I`` (1/s^2) at the package's defaults
    (1 and 0.3).

Frames: the packages work in their own inertial frame (VQF and the ``ahrs`` Mahony: east,
north, up; Madgwick: north, west, up; "north" being the horizontal Earth field) and take the accelerometer's specific
force as "up", so the body frame needs no change. The estimate is turned into this package's
inertial frame, the one of the ``gravity`` and ``earth_field`` references, by the constant
rotation between the two frames built from those references.
"""

from __future__ import annotations

import numpy as np
from quadcosim.estimators import core

#: The third-party reference filters this module runs, by name.
REFERENCE_FILTERS = ("vqf", "madgwick", "mahony")
DEFAULT_GAINS = {"vqf": {}, "madgwick": {"beta": 0.041}, "mahony": {"k_P": 1.0, "k_I": 0.3}}


def _vqf_parameters() -> dict:
    from vqf import VQF

    return dict(VQF(gyrTs=0.01).params)


def check_gains(kind: str, gains: dict | None) -> dict:
    """Scalar gains of the published filter ``kind`` (``vqf`` or ``madgwick``) by name, defaults
    filled in; unknown names refused."""
    known = _vqf_parameters() if kind == "vqf" else dict(DEFAULT_GAINS[kind])
    merged = dict(DEFAULT_GAINS[kind])
    for name, value in (gains or {}).items():
        if name not in known:
            raise ValueError(f"the {kind} filter has no gain {name!r}; its gains are {', '.join(known)}")
        merged[name] = value
    return merged


def _gain_sets(kind, gains) -> list[dict]:
    merged = check_gains(kind, gains)
    arrays = {k: np.atleast_1d(v) for k, v in merged.items()}
    sizes = {len(a) for a in arrays.values() if len(a) > 1}
    if len(sizes) > 1:
        raise ValueError(f"array-valued gains must share one length, not {sorted(sizes)}")
    count = sizes.pop() if sizes else 1
    return [{k: (a[g] if len(a) > 1 else a[0]).item() for k, a in arrays.items()} for g in range(count)]


def frame_rotation(kind: str, config) -> np.ndarray:
    """Quaternion of the rotation from the inertial frame of the package of ``kind`` to the one of
    the configuration vector ``config``."""
    g = config[core.GRAVITY:core.GRAVITY + 3]
    m = config[core.FIELD:core.FIELD + 3]
    up = -g / np.linalg.norm(g)
    north = m - (m @ up) * up
    north /= np.linalg.norm(north)
    if kind in ("vqf", "mahony"):
        columns = (np.cross(north, up), north, up)
    else:
        columns = (north, np.cross(up, north), up)
    q = np.empty(4)
    core.quaternion_from_rotation(np.column_stack(columns), q)
    return q


def _conjugate(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


class _Runner:
    """One published filter, advanced one sample at a time, in this package's frames."""

    def __init__(self, kind, gains, config, dt, q0, from_triad):
        self.kind, self.dt, self.config = kind, dt, config
        self.to_ours = frame_rotation(kind, config)
        self.from_ours = _conjugate(self.to_ours)
        self.q = np.empty(4)
        self.bias = np.zeros(3)
        self.flags = np.array([1.0, 1.0, 0.0])
        if kind == "vqf":
            from vqf import VQF

            self.filter = VQF(dt, **gains)
        else:
            from ahrs.filters import Madgwick, Mahony

            if kind == "mahony":
                self.filter = Mahony(frequency=1.0 / dt, k_P=gains["k_P"], k_I=gains["k_I"])
            else:
                self.filter = Madgwick(gain=gains["beta"], frequency=1.0 / dt)
            self.state = np.empty(4)
            core.quaternion_multiply(self.from_ours, q0, self.state)
        self.pending = from_triad
        self.sample = np.empty((3, 3))

    def step(self, acc, gyro, mag):
        """Advance by one sample; ``self.q`` is the estimate, body to the configured frame."""
        if self.kind == "vqf":
            gyr, a, m = (np.ascontiguousarray(v, dtype=float) for v in (gyro, acc, mag))
            self.filter.update(gyr, a, m)
            quaternion = self.filter.getQuat9D()
            self.bias[:] = self.filter.getBiasEstimate()[0]
            self.flags[1] = 0.0 if self.filter.getMagDistDetected() else 1.0
            self.flags[2] = 1.0 if self.filter.getRestDetected() else 0.0
        else:
            if self.pending:
                self.pending = False
                r = np.empty((3, 3))
                if core.triad(np.asarray(acc, float), np.asarray(mag, float), self.config, r):
                    start = np.empty(4)
                    core.quaternion_from_rotation(r, start)
                    core.quaternion_multiply(self.from_ours, start, self.state)
            self.state = self.filter.updateMARG(self.state, gyr=np.asarray(gyro, float), acc=np.asarray(acc, float),
                                                mag=np.asarray(mag, float), dt=self.dt)
            quaternion = self.state
            if self.kind == "mahony":
                self.bias[:] = self.filter.b
        core.quaternion_multiply(self.to_ours, quaternion, self.q)
        if self.q[0] < 0:
            self.q *= -1.0


def _write(runner, gyro, y):
    y[core.OUT_Q:core.OUT_Q + 4] = runner.q
    core.euler_from_quaternion(runner.q, y[core.OUT_THETA:core.OUT_THETA + 3])
    y[core.OUT_B:core.OUT_B + 3] = runner.bias
    y[core.OUT_OMEGA:core.OUT_OMEGA + 3] = gyro - runner.bias
    y[core.OUT_WEIGHTS:core.OUT_WEIGHTS + 3] = runner.flags


def streaming_step(kind, gains, config, dt, q0, b0, from_triad):
    """A block's ``step(t, u, y)`` running the published filter ``kind`` with ``gains`` on the
    inputs ``acc, gyro, mag``, every ``dt`` (s), in the frame of ``config``, from ``q0`` (body to
    inertial, scalar first; or TRIAD, ``from_triad``); ``b0`` is taken for the common signature
    and not used."""
    runner = _Runner(kind, check_gains(kind, gains), config, dt, q0, from_triad)
    acc, gyro, mag = slice(core.ACC, core.ACC + 3), slice(core.GYRO, core.GYRO + 3), slice(core.MAG, core.MAG + 3)

    def step(t, u, y):
        runner.step(u[acc], u[gyro], u[mag])
        _write(runner, u[gyro], y)

    return step


def _vqf_batch(gains, config, dt, inputs) -> np.ndarray:
    """VQF's attitude (N, 4) over the samples ``inputs`` by the package's batch update, in the frame of
    ``config``."""
    from vqf import VQF

    acc, gyro, mag = (np.ascontiguousarray(inputs[:, start:start + 3]) for start in (core.ACC, core.GYRO, core.MAG))
    quat = VQF(dt, **gains).updateBatch(gyro, acc, mag)["quat9D"]
    to_ours = frame_rotation("vqf", config)
    out = np.empty_like(quat)
    for n in range(len(quat)):
        core.quaternion_multiply(to_ours, quat[n], out[n])
    out *= np.where(out[:, :1] < 0, -1.0, 1.0)
    return out


def estimate(kind, inputs, dt, gains, config, q0, b0, from_triad, outputs) -> dict:
    """The published filter ``kind`` on recorded samples ``inputs`` (N, 9: acc, gyro, mag), every
    ``dt`` (s), per gain set of ``gains``, in the frame of ``config``, from ``q0`` (or TRIAD,
    ``from_triad``); ``b0`` is taken for the common signature and not used; ``outputs`` names
    the outputs to keep.

    Returns the requested outputs (G, N, size) as :func:`quadcosim.estimators.estimate` does, and
    ``q_all`` (G, N, 4) for scoring.
    """
    sets = _gain_sets(kind, gains)
    count = len(inputs)
    q_all = np.empty((len(sets), count, 4))
    kept = {name: np.empty((len(sets), count, core.OUTPUT_SLOTS[name][1] - core.OUTPUT_SLOTS[name][0]))
            for name in outputs}
    y = np.empty(core.OUTPUT_SIZE)
    for g, gain_set in enumerate(sets):
        if kind == "vqf" and set(outputs) <= {"q"}:
            q_all[g] = _vqf_batch(gain_set, config, dt, inputs)  # the same updates, in one call into the package
            for array in kept.values():
                array[g] = q_all[g]
            continue
        runner = _Runner(kind, gain_set, config, dt, q0, from_triad)
        for n in range(count):
            u = inputs[n]
            runner.step(u[core.ACC:core.ACC + 3], u[core.GYRO:core.GYRO + 3], u[core.MAG:core.MAG + 3])
            _write(runner, u[core.GYRO:core.GYRO + 3], y)
            q_all[g, n] = runner.q
            for name, array in kept.items():
                array[g, n] = y[slice(*core.OUTPUT_SLOTS[name])]
    return kept | {"q_all": q_all}
