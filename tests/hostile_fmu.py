"""FMUs that misbehave on purpose, built from C at test time: a motor model with the interface the
open-loop scenario reads of MotorMagnetics (commands c1..c4 in, rotor speeds, accelerations,
currents and a magnetic field out), whose C source is compiled once per behaviour.

Each behaviour (:data:`BEHAVIOURS`) strikes at the macro step :data:`FAULT_STEP` (or at set-up):
the run has recorded that many samples before it. Nothing here is committed as a binary.
"""

from __future__ import annotations

import shutil
import subprocess
import uuid
import zipfile
import zlib
from pathlib import Path

FAULT_STEP = 100
TAU, OMEGA_MAX, CURRENT_MAX = 0.03, 1000.0, 20.0  # s, rad/s, A

#: behaviour -> what it does
BEHAVIOURS = {
    "good": "a first-order motor, well behaved",
    "hang_step": "fmi2DoStep loops forever at the fault step",
    "hang_init": "fmi2ExitInitializationMode loops forever",
    "hang_instantiate": "fmi2Instantiate loops forever",
    "segfault": "fmi2DoStep writes through a null pointer at the fault step",
    "abort": "fmi2DoStep calls abort() at the fault step",
    "exit0": "fmi2DoStep calls exit(0) at the fault step",
    "null_instance": "fmi2Instantiate returns NULL",
    "status_m1": "fmi2DoStep returns -1 from the fault step on",
    "bad_vr": "the description declares an output at a value reference the model does not hold",
    "no_do_step": "the binary has no fmi2DoStep",
    "noop_reset": "fmi2Reset returns OK and resets nothing",
    "reset_error": "fmi2Reset returns fmi2Error",
}

SOURCE = r"""
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"

#define NVARS 21 /* tau, omega_max, c1..4, omega_r1..4, domega_r1..4, i1..4, b_d_x..z */
#define FAULT_STEP %(fault_step)d
enum { HANG_STEP = 1, HANG_INIT, HANG_INSTANTIATE, SEGFAULT, ABORT, EXIT0, NULL_INSTANCE, STATUS_M1, BAD_VR,
       NO_DO_STEP, NOOP_RESET, RESET_ERROR };
#define BEHAVIOUR %(behaviour)d

typedef struct { double r[NVARS]; long steps; fmi2CallbackFunctions cb; fmi2String name; } Model;

static volatile int forever = 1;
static void spin(void) { while (forever) { } }

static void defaults(Model *m) {
    memset(m->r, 0, sizeof m->r);
    m->r[0] = %(tau)r; m->r[1] = %(omega_max)r;
    m->steps = 0;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    (void)c; (void)on; (void)n; (void)cats; return fmi2OK; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String resources,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging) {
    Model *m;
    (void)type; (void)guid; (void)resources; (void)visible; (void)logging;
    if (BEHAVIOUR == HANG_INSTANTIATE) spin();
    if (BEHAVIOUR == NULL_INSTANCE) {
        cb->logger(cb->componentEnvironment, name, fmi2Error, "error", "this FMU never makes an instance");
        return NULL;
    }
    m = calloc(1, sizeof *m);
    m->cb = *cb;
    m->name = name;
    defaults(m);
    return m;
}
void fmi2FreeInstance(fmi2Component c) { free(c); }
fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean a, fmi2Real b, fmi2Real t0, fmi2Boolean d, fmi2Real e) {
    (void)c; (void)a; (void)b; (void)t0; (void)d; (void)e; return fmi2OK; }
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    (void)c;
    if (BEHAVIOUR == HANG_INIT) spin();
    return fmi2OK;
}
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) {
    if (BEHAVIOUR == RESET_ERROR) return fmi2Error;
    if (BEHAVIOUR != NOOP_RESET) defaults((Model *)c);
    return fmi2OK;
}

static fmi2Status bad_reference(Model *m, fmi2ValueReference r) {
    m->cb.logger(m->cb.componentEnvironment, m->name, fmi2Error, "error", "unknown value reference %%u", r);
    return fmi2Error;
}
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Model *m = c; size_t k;
    for (k = 0; k < n; k++) { if (vr[k] >= NVARS) return bad_reference(m, vr[k]); v[k] = m->r[vr[k]]; }
    return fmi2OK;
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    Model *m = c; size_t k;
    for (k = 0; k < n; k++) { if (vr[k] >= NVARS) return bad_reference(m, vr[k]); m->r[vr[k]] = v[k]; }
    return fmi2OK;
}
#define NOT_HERE(f, args) fmi2Status f args { return fmi2Error; }
NOT_HERE(fmi2GetInteger, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]))
NOT_HERE(fmi2SetInteger, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]))
NOT_HERE(fmi2GetBoolean, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]))
NOT_HERE(fmi2SetBoolean, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]))
NOT_HERE(fmi2GetString, (fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]))
NOT_HERE(fmi2SetString, (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]))
NOT_HERE(fmi2GetFMUstate, (fmi2Component c, fmi2FMUstate *s))
NOT_HERE(fmi2SetFMUstate, (fmi2Component c, fmi2FMUstate s))
NOT_HERE(fmi2FreeFMUstate, (fmi2Component c, fmi2FMUstate *s))
NOT_HERE(fmi2SerializedFMUstateSize, (fmi2Component c, fmi2FMUstate s, size_t *n))
NOT_HERE(fmi2SerializeFMUstate, (fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n))
NOT_HERE(fmi2DeSerializeFMUstate, (fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s))
NOT_HERE(fmi2GetDirectionalDerivative, (fmi2Component c, const fmi2ValueReference a[], size_t na,
         const fmi2ValueReference b[], size_t nb, const fmi2Real d[], fmi2Real e[]))
NOT_HERE(fmi2SetRealInputDerivatives, (fmi2Component c, const fmi2ValueReference vr[], size_t n,
         const fmi2Integer o[], const fmi2Real v[]))
NOT_HERE(fmi2GetRealOutputDerivatives, (fmi2Component c, const fmi2ValueReference vr[], size_t n,
         const fmi2Integer o[], fmi2Real v[]))
NOT_HERE(fmi2CancelStep, (fmi2Component c))
NOT_HERE(fmi2GetStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Status *v))
NOT_HERE(fmi2GetRealStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Real *v))
NOT_HERE(fmi2GetIntegerStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Integer *v))
NOT_HERE(fmi2GetBooleanStatus, (fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v))
NOT_HERE(fmi2GetStringStatus, (fmi2Component c, const fmi2StatusKind s, fmi2String *v))

#if %(has_do_step)d
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    Model *m = c; int n;
    (void)t; (void)no_prior;
    if (m->steps++ >= FAULT_STEP) {
        switch (BEHAVIOUR) {
        case HANG_STEP: spin(); break;
        case SEGFAULT: *(volatile double *)(size_t)forever = 1.0; break;
        case ABORT: abort();
        case EXIT0: exit(0);
        case STATUS_M1: return (fmi2Status)-1;
        default: break;
        }
    }
    for (n = 0; n < 4; n++) {  /* explicit Euler, d omega / dt = (c omega_max - omega) / tau */
        double command = m->r[2 + n] < 0.0 ? 0.0 : m->r[2 + n] > 1.0 ? 1.0 : m->r[2 + n];
        double rate = (command * m->r[1] - m->r[6 + n]) / m->r[0];
        m->r[10 + n] = rate;
        m->r[6 + n] += rate * h;
        m->r[14 + n] = command * %(current_max)r;
    }
    return fmi2OK;
}
#endif
"""


def _description(behaviour: str, guid: str) -> str:
    names = ["tau", "omega_max", *(f"c{n}" for n in range(1, 5)), *(f"omega_r{n}" for n in range(1, 5)),
             *(f"domega_r{n}" for n in range(1, 5)), *(f"i{n}" for n in range(1, 5)),
             *(f"b_d_{a}" for a in "xyz")]
    units = {"omega_r": "rad/s", "domega_r": "rad/s2", "i": "A", "b_d_": "T", "c": "1"}
    rows, outputs = [], []
    for ref, name in enumerate(names):
        causality = "parameter" if ref < 2 else "input" if ref < 6 else "output"
        if behaviour == "bad_vr" and name == "b_d_z":
            ref = 99  # nothing in the model holds it
        unit = next((u for prefix, u in units.items() if name.startswith(prefix) and causality != "parameter"), "")
        start = {"tau": f' start="{TAU!r}"', "omega_max": f' start="{OMEGA_MAX!r}"'}.get(name, ' start="0"')
        extra = ' variability="fixed"' if causality == "parameter" else ""
        if causality == "output":
            extra += ' initial="exact"'
            outputs.append(len(rows) + 1)
        rows.append(f'    <ScalarVariable name="{name}" valueReference="{ref}" causality="{causality}"{extra}>'
                    f'<Real{f" unit=\"{unit}\"" if unit else ""}{start}/></ScalarVariable>')
    units_xml = "".join(f'<Unit name="{u}"/>' for u in ("rad/s", "rad/s2", "A", "T", "1"))
    structure = "".join(f'<Unknown index="{k}" dependencies=""/>' for k in outputs)
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<fmiModelDescription fmiVersion="2.0" modelName="Hostile" '
            f'guid="{guid}" generationTool="a test of hostile FMUs" variableNamingConvention="flat" '
            f'numberOfEventIndicators="0">\n  <CoSimulation modelIdentifier="Hostile" '
            f'canHandleVariableCommunicationStepSize="true"/>\n  <UnitDefinitions>{units_xml}</UnitDefinitions>\n'
            f'  <ModelVariables>\n' + "\n".join(rows) + "\n  </ModelVariables>\n"
            f"  <ModelStructure><Outputs>{structure}</Outputs></ModelStructure>\n</fmiModelDescription>\n")


def build(behaviour: str, folder: Path, fault_step: int = FAULT_STEP) -> Path:
    """Compile the motor with ``behaviour`` into ``folder/<behaviour>.fmu``.

    Parameters
    ----------
    behaviour : str
        One of :data:`BEHAVIOURS`.
    folder : pathlib.Path
        Where the FMU and its build files go.
    fault_step : int
        The macro step at which the behaviour strikes.

    Returns
    -------
    pathlib.Path
    """
    from quadcosim.fmus.build import _fmi_header_dir

    code = list(BEHAVIOURS).index(behaviour)  # 0 good, then the enum's order
    stage = folder / f"{behaviour}.stage"
    shutil.rmtree(stage, ignore_errors=True)
    (stage / "binaries" / "linux64").mkdir(parents=True)
    source = stage / "hostile.c"
    source.write_text(SOURCE % {"fault_step": fault_step, "behaviour": code, "tau": TAU, "omega_max": OMEGA_MAX,
                                "current_max": CURRENT_MAX,
                                "has_do_step": int(behaviour != "no_do_step")})
    subprocess.run(["cc", "-std=c99", "-O1", "-fPIC", "-shared", "-I", str(_fmi_header_dir()), "-o",
                    str(stage / "binaries" / "linux64" / "Hostile.so"), str(source)], check=True,
                   capture_output=True)
    path = folder / f"{behaviour}.fmu"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("modelDescription.xml", _description(behaviour, "{" + str(uuid.uuid4()) + "}"))
        archive.write(stage / "binaries" / "linux64" / "Hostile.so", "binaries/linux64/Hostile.so")
    shutil.rmtree(stage)
    return path


def repacked(source: Path, target: Path, rename: dict | None = None, add: dict | None = None,
             drop: tuple = ()) -> Path:
    """A copy of an FMU with entries renamed (``{old: new}``), added (``{name: bytes}``) or dropped."""
    rename = rename or {}
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(target, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            if item.filename not in drop:
                zout.writestr(rename.get(item.filename, item.filename), zin.read(item.filename))
        for name, data in (add or {}).items():
            zout.writestr(name, data)
    return target


def _crc32_combine(crc1: int, crc2: int, length2: int) -> int:
    """zlib's crc32_combine: the CRC-32 of two blocks from theirs and the second's length."""
    def times(matrix, vector):
        total, k = 0, 0
        while vector:
            if vector & 1:
                total ^= matrix[k]
            vector >>= 1
            k += 1
        return total

    def square(matrix):
        return [times(matrix, m) for m in matrix]

    odd = [0xEDB88320] + [1 << n for n in range(31)]
    even = square(odd)
    odd = square(even)
    while True:
        even = square(odd)
        if length2 & 1:
            crc1 = times(even, crc1)
        length2 >>= 1
        if not length2:
            break
        odd = square(even)
        if length2 & 1:
            crc1 = times(odd, crc1)
        length2 >>= 1
        if not length2:
            break
    return crc1 ^ crc2


def zip_bomb(source: Path, target: Path, chunks: int = 61, chunk: int = 64 << 20) -> Path:
    """``source`` with a resource of ``chunks * chunk`` zero bytes (3.8 GiB by default) deflated
    into a few MB: a real, valid entry (its CRC correct), written without expanding it."""
    compressor = zlib.compressobj(9, zlib.DEFLATED, -15)
    block = compressor.compress(bytes(chunk)) + compressor.flush(zlib.Z_FULL_FLUSH)
    tail = zlib.compressobj(9, zlib.DEFLATED, -15).flush(zlib.Z_FINISH)  # an empty final block
    crc_chunk = zlib.crc32(bytes(chunk))
    crc = crc_chunk
    for _ in range(chunks - 1):
        crc = _crc32_combine(crc, crc_chunk, chunk)
    data = block * chunks + tail
    repacked(source, target)
    name = b"resources/zeros.bin"
    with zipfile.ZipFile(target, "a", zipfile.ZIP_STORED) as archive:
        archive.writestr(zipfile.ZipInfo(name.decode()), data)  # stored now, then marked deflated below
    raw = bytearray(target.read_bytes())
    size = chunks * chunk
    local = raw.rindex(b"PK\x03\x04", 0, raw.index(name))  # its local header, before its data
    raw[local + 8:local + 10] = (8).to_bytes(2, "little")
    raw[local + 14:local + 18] = crc.to_bytes(4, "little")
    raw[local + 22:local + 26] = size.to_bytes(4, "little")
    central = raw.rindex(b"PK\x01\x02", 0, raw.rindex(name))  # its entry in the directory, at the end
    raw[central + 10:central + 12] = (8).to_bytes(2, "little")
    raw[central + 16:central + 20] = crc.to_bytes(4, "little")
    raw[central + 24:central + 28] = size.to_bytes(4, "little")
    target.write_bytes(bytes(raw))
    return target
