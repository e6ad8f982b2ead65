"""cffi (API mode) build of the C core into ``accelcal._core``.

The cdef is generated from the real public headers, so it cannot drift from
them; API mode then compiles every declaration against those same headers,
which catches any mismatch at build time.
"""
from __future__ import annotations

import re
from pathlib import Path

from cffi import FFI

ROOT = Path(__file__).resolve().parents[2]
INCLUDE = ROOT / "include"
CSRC = ROOT / "csrc"
#: host-only C of the extension, apart from the firmware core's csrc/ (no firmware build takes it)
HOST = ROOT / "hostsrc"
HEADERS = ["ac_status.h", "ac_fixed.h", "ac_xf.h", "ac_trim.h", "ac_resolve.h", "ac_trig.h", "ac_attitude.h",
           "ac_invert.h", "ac_rate.h"]
HEADERS += ["ac_rest.h", "ac_displace.h"]  # motion estimators
HEADERS += ["ac_temp.h", "ac_skew.h", "ac_nonlin.h"]  # the correctable terms
HEADERS += ["ac_omega.h"]  # the array's own omega (issue 36)


def config_constants(include_dir: Path = INCLUDE) -> dict[str, int]:
    """The integer #define defaults of ac_config.h (AC_MAX_CHANNELS, the Q formats...)."""
    text = (include_dir / "accelcal" / "ac_config.h").read_text()
    return {m.group(1): int(m.group(2))
            for m in re.finditer(r"^#define\s+(AC_[A-Z0-9_]+)\s+(-?\d+)\s*$", text, re.M)}


def _cdef_of(header: Path, consts: dict[str, int]) -> str:
    """One header as cdef text: comments and preprocessor lines dropped, integer
    #defines kept, the config constants substituted."""
    text = re.sub(r"/\*.*?\*/", "", header.read_text(), flags=re.S)
    text = re.sub(r"//[^\n]*", "", text)
    lines = []
    for line in text.splitlines():
        m = re.match(r"#define\s+(AC[A-Z0-9_]*_[A-Z0-9_]+)\s+\(?(0x[0-9A-Fa-f]+|-?\d+)u?\)?\s*$", line.strip())
        if m:
            lines.append(f"#define {m.group(1)} {int(m.group(2), 0)}")
        elif not line.lstrip().startswith("#"):
            lines.append(line)
    body = "\n".join(lines)
    for k, v in consts.items():
        body = re.sub(rf"\b{k}\b", str(v), body)
    return body


def cdef_from_headers(include_dir: Path = INCLUDE) -> str:
    consts = config_constants(include_dir)
    out = [f"#define {k} {v}" for k, v in consts.items() if k != "AC_NO_STDINT"]
    out += [_cdef_of(include_dir / "accelcal" / name, consts) for name in HEADERS]
    return "\n".join(out)


#: the host-only C's headers (HOST): the CSV formatter
HOST_HEADERS = ["fmt_csv.h"]

ffibuilder = FFI()
ffibuilder.cdef(cdef_from_headers() + "\n" + "\n".join(_cdef_of(HOST / h, {}) for h in HOST_HEADERS))
ffibuilder.set_source(
    "accelcal._core",
    '#include "accelcal/accelcal.h"\n' + "".join(f'#include "{h}"\n' for h in HOST_HEADERS),
    sources=[str(p.relative_to(ROOT)) for p in sorted(CSRC.glob("*.c")) + sorted(HOST.glob("*.c"))],
    include_dirs=[str(INCLUDE), str(CSRC), str(HOST)],
    extra_compile_args=["-std=c99", "-O2"],
)

if __name__ == "__main__":
    ffibuilder.compile(verbose=True)
