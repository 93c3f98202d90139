"""Public real recordings with optical ground truth, read from a data folder (not shipped).

Each dataset sits in its own sub-folder of the data folder, as its authors publish it:

``broad/``
    BROAD (Laidig, Caruso, Cereatti, Seel, "BROAD—A Benchmark for Robust Inertial Orientation
    Estimation", Data, 2021; CC BY 4.0): the ``.mat`` files of its ``data_mat`` folder. A
    custom IMU at 286 Hz, rotations and translations, slow and fast, with tapping, vibration and
    magnets. Reference in ENU, aligned to the IMU; scored over the movement phases, heading as is.
``smartphones/``
    "On attitude estimation with smartphones" (Michel, Genevès, Fourati, Layaïda, PerCom
    2017; CeCILL licence): its ``android`` and ``qualisys`` folders. A Nexus 5 carried by three
    people (texting, phoning, swinging, in pockets, augmented reality, running in the hand or in
    a pocket), with and without magnetic disturbances; a Qualisys system at 60 Hz. The phone's
    calibrated gyro, accelerometer and magnetometer are resampled to 100 Hz; the reference is
    aligned (:mod:`quadcosim.estimators.alignment`: body and vertical rotations, then the heading).
``diodem/``
    The dataset recorded for RING (Bachhuber, Weygers, Lehmann, Dammann, Seel, "RING: a
    recurrent inertial graph-based estimator", supplementary material; folders ``trial1`` and
    ``trial2`` of its ``data/dataset``): five segments of a kinematic chain moved by hand, an
    IMU rigidly on each (40 Hz), optical reference at 30 Hz. Aligned as the smartphones.
``iphones/``
    The same smartphone dataset's iPhone 4S and iPhone 5 recordings: its ``ios`` and
    ``qualisys`` folders, the same people and motions; the raw gyro (iOS gives no calibrated
    one), the accelerometer in g (its sign turned: iOS reads minus the specific force) and the
    calibrated magnetometer, read and aligned as the Nexus 5's. Held out: never read before the
    defaults were frozen.
``repoimu/``
    RepoIMU (Szczęsna, Skurowski, Pruszowski, Pęszor, Paszkuta, Wojciechowski, "Reference
    Data Set for Accuracy Evaluation of Orientation Estimation Algorithms for Inertial Motion
    Capture Systems", ICCVG 2016): its pendulum recordings (``Pendulum_*.csv``), an IMU on a
    swinging pendulum with a Vicon reference. Aligned as the smartphones.

A recording whose reference does not turn as its gyro does (:func:`usable`), or cannot be aligned
at all, is left out.
Every loader gives recordings as :func:`quadcosim.estimators.recording.load` does (``gyro``, ``acc``,
``mag``, ``rate``, ``quat``, ``scored``, ``meta``), with ``meta["align"]`` saying whether the
heading offset is removed when scoring.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from quadcosim.estimators import alignment, recording

PHONE_RATE = 100.0  # Hz, the grid the phones' unevenly timed sensors are resampled to
TIME_SEARCH_S = 4.0  # s, span searched for the phones' clock offset
MISMATCH_LIMIT = 0.3  # a recording whose gyro and reference rates differ by more (relative median) is not used


def broad(folder: Path):
    """BROAD's recordings in ``folder`` (its ``.mat`` files), as they are."""
    for path in sorted(folder.glob("*.mat")):
        data = recording.load(path)
        data["meta"] = {"frame": "enu", "align": False}
        yield path.stem, data


def _aligned(gyro, acc, mag, rate, quat):
    try:
        quat = alignment.align(gyro, acc, quat, 1.0 / rate)
        mismatch = alignment.rate_mismatch(gyro, quat, 1.0 / rate)
    except ValueError:  # the reference never turns while the gyro does (tracking lost): left out by usable()
        quat, mismatch = np.full_like(quat, np.nan), math.inf
    return {"gyro": gyro, "acc": acc, "mag": mag, "rate": rate, "quat": quat,
            "scored": np.isfinite(quat).all(axis=1),
            "meta": {"frame": "enu", "align": True, "rate_mismatch": mismatch}}


def _csv_with_comments(path: Path) -> tuple[dict, float]:
    lines = path.read_text().splitlines()
    rate = float(lines[0].split(":")[1])
    names = lines[2].split(",")
    values = np.genfromtxt(lines[3:], delimiter=",")
    return {name: values[:, k] for k, name in enumerate(names)}, rate


def diodem(folder: Path):
    """The RING dataset's segments in ``folder`` (``trial1``, ``trial2``), each an aligned recording."""
    for trial in sorted(p for p in folder.iterdir() if p.is_dir()):
        imu, rate = _csv_with_comments(trial / "imu_rigid.csv")
        omc, omc_rate = _csv_with_comments(trial / "omc.csv")
        for segment in range(1, 6):
            def stack(table, kind, axes, s=segment):
                return np.column_stack([table[f"seg{s}_{kind}_{a}"] for a in axes])

            gyro, acc, mag = (stack(imu, k, "xyz") for k in ("gyr", "acc", "mag"))
            time = np.arange(len(gyro)) / rate
            quat = alignment.resample(np.arange(len(omc["seg1_quat_w"])) / omc_rate, stack(omc, "quat", "wxyz"), time)
            yield f"{trial.name}_seg{segment}", _aligned(gyro, acc, mag, rate, quat)


def repoimu(folder: Path):
    """RepoIMU's pendulum recordings in ``folder``, each aligned."""
    for path in sorted(folder.glob("Pendulum_*.csv")):
        table = np.genfromtxt(path, delimiter=";", skip_header=2)
        _, first = np.unique(table[:, 0], return_index=True)  # repeated time stamps: the first kept
        table = table[np.sort(first)]
        table = table[np.r_[True, np.diff(table[:, 0]) > 0]]
        time, quat = table[:, 0], table[:, 1:5]
        acc, gyro, mag = table[:, 5:8], table[:, 8:11], table[:, 11:14]
        rate = 1.0 / float(np.median(np.diff(time)))
        quat = np.where(np.all(quat == 0.0, axis=1)[:, None], np.nan, quat)  # all zero: Vicon lost the body
        if not np.isfinite(quat).all(axis=1).any():  # no reference at all (the static trials): left out
            yield path.stem, {"meta": {"frame": "enu", "align": True, "rate_mismatch": math.inf}}
            continue
        grid = np.arange(int((time[-1] - time[0]) * rate)) / rate + time[0]
        sensors = [np.column_stack([np.interp(grid, time, v[:, k]) for k in range(3)]) for v in (gyro, acc, mag)]
        yield path.stem, _aligned(*sensors, rate, alignment.resample(time, quat, grid))


def _phone_sensor(path: Path, grid):
    table = np.loadtxt(path, usecols=(0, 1, 2, 3))
    return np.column_stack([np.interp(grid, table[:, 0], table[:, k]) for k in (1, 2, 3)])


def _qualisys(path: Path):
    """Times (s) and rotation matrices (M, 3, 3, body to capture frame) of the one rigid body of a
    Qualisys export; NaN where the body was not tracked."""
    from scipy.io import loadmat

    export = next(v for k, v in loadmat(path).items() if not k.startswith("__"))[0, 0]
    body = export["RigidBodies"][0, 0]
    elements = body["Rotations"][0]  # (9, M), column after column
    rotations = elements.T.reshape(-1, 3, 3).transpose(0, 2, 1)
    return np.arange(rotations.shape[0]) / float(export["FrameRate"][0, 0]), rotations


def _clock_offset(gyro, grid, quat_time, quat):
    """Offset (s) to add to the phone's clock to reach the capture's, by the best match of the
    angular-rate norms over :data:`TIME_SEARCH_S` either side."""
    dt = 1.0 / PHONE_RATE
    rate_norm = np.linalg.norm(gyro, axis=1)
    ref_rates = np.linalg.norm(alignment.body_rates(quat, quat_time[1] - quat_time[0]), axis=1)
    offsets = np.arange(-TIME_SEARCH_S, TIME_SEARCH_S, dt)
    scores = []
    for offset in offsets:
        shifted = np.interp(grid + offset, quat_time, np.nan_to_num(ref_rates), left=np.nan, right=np.nan)
        known = np.isfinite(shifted)
        scores.append(np.corrcoef(rate_norm[known], shifted[known])[0, 1] if known.sum() > 100 else -1.0)
    return float(offsets[int(np.argmax(scores))])


IOS_G = 9.80665  # m/s^2 per g: the iPhones' accelerometer reads in g
# each platform's sensor files (gyro, accelerometer, magnetometer) and the factor turning its accelerometer
# into the specific force in m/s^2: Android's reads it in m/s^2, iOS's reads minus it in g (-1 g along z
# lying face up)
PHONES = {"android": (("gyroscope-calibrated", "accelerometer", "magnetometer-calibrated"), 1.0, "*_Nexus5_*"),
          "ios": (("gyroscope", "accelerometer", "magnetometer-calibrated"), -IOS_G, "*_iPhone*_*")}


def _boot_time(phone: Path) -> float:
    """The phone clock's time (s) at the recording's start: ``BootTime`` of its ``description.txt``
    (the iPhones count from the phone's boot), 0 without one (the Nexus 5 counts from the start)."""
    description = phone / "description.txt"
    if description.exists():
        for line in description.read_text().splitlines():
            name, _, value = line.partition("=")
            if name.strip() == "BootTime":
                return float(value)
    return 0.0


def _phones(folder: Path, platform: str):
    """The recordings of one platform of the smartphone dataset in ``folder`` (its ``android`` or ``ios``
    folder and ``qualisys``), each on a 100 Hz grid, its clock matched to the capture's, aligned."""
    from scipy.spatial.transform import Rotation

    sensors, acc_scale, pattern = PHONES[platform]
    for phone in sorted((folder / platform).glob(pattern)):
        capture = folder / "qualisys" / f"{phone.name}.mat"
        if not capture.exists():
            continue
        start = max(np.loadtxt(phone / f"{n}.txt", usecols=0)[0] for n in sensors)
        stop = min(np.loadtxt(phone / f"{n}.txt", usecols=0)[-1] for n in sensors)
        grid = np.arange(start, stop, 1.0 / PHONE_RATE)
        gyro, acc, mag = (_phone_sensor(phone / f"{n}.txt", grid) for n in sensors)
        quat_time, rotations = _qualisys(capture)
        tracked = np.isfinite(rotations).all(axis=(1, 2))
        quat = np.full((len(rotations), 4), np.nan)
        quat[tracked] = alignment._quaternion(Rotation.from_matrix(rotations[tracked]))
        local = grid - _boot_time(phone)  # s from the recording's start, as the capture's clock counts
        offset = _clock_offset(gyro, local, quat_time, quat)
        data = _aligned(gyro, acc_scale * acc, mag, PHONE_RATE, alignment.resample(quat_time, quat, local + offset))
        data["meta"]["clock_offset_s"] = offset
        yield phone.name, data


def smartphones(folder: Path):
    """The Nexus 5 recordings of the smartphone dataset in ``folder`` (``android``, ``qualisys``), each
    on a 100 Hz grid, its clock matched to the capture's, aligned."""
    yield from _phones(folder, "android")


def iphones(folder: Path):
    """The iPhone 4S and iPhone 5 recordings of the smartphone dataset in ``folder`` (``ios``,
    ``qualisys``): raw gyro, accelerometer turned into the specific force in m/s^2, calibrated
    magnetometer, each on a 100 Hz grid, its clock matched to the capture's, aligned."""
    yield from _phones(folder, "ios")


def usable(data: dict) -> bool:
    """Whether the recording ``data`` can score a filter: its reference turns as its gyro does
    (:func:`quadcosim.estimators.alignment.rate_mismatch` under :data:`MISMATCH_LIMIT`). A recording whose
    reference lost track of its body, or whose clocks could not be matched, is left out."""
    return data["meta"].get("rate_mismatch", 0.0) < MISMATCH_LIMIT


LOADERS = {"broad": broad, "smartphones": smartphones, "diodem": diodem, "repoimu": repoimu, "iphones": iphones}


def load(data_folder, name: str, left_out: list | None = None):
    """The recordings of the dataset ``name`` (a key of :data:`LOADERS`) under ``data_folder``, as
    (recording name, recording) pairs; none when its sub-folder is absent. The names of those not
    :func:`usable` are appended to ``left_out`` when it is given."""
    folder = Path(data_folder) / name
    if not folder.is_dir():
        return []
    kept = []
    for label, data in LOADERS[name](folder):
        if usable(data):
            kept.append((label, data))
        elif left_out is not None:
            left_out.append(label)
    return kept
