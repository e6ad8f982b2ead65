#!/usr/bin/env python3
"""Wrap an h8300-hms COFF executable in a minimal ELF32 for GNU's H8 simulator.

GDB 13's simulator reads ELF only and the Debian H8 toolchain (binutils 2.16.1)
writes COFF only.  The COFF's loadable sections are flattened with
``h8300-hms-objcopy -O binary`` and written as one ELF32 big-endian segment
(``e_machine`` 46, EM_H8_300) at the lowest loaded address, with the COFF's start
address as ``e_entry``.  ``e_flags`` 0x00830000 (E_H8_MACH_H8300HN) makes the
simulator run an H8/300H in normal mode, the seed's H8/3664.

Usage: elfwrap.py [--cross PREFIX] input.coff output.elf
"""
import argparse
import re
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

EM_H8_300 = 46
E_H8_MACH_H8300HN = 0x00830000
SHF_WRITE, SHF_ALLOC, SHF_EXECINSTR = 1, 2, 4


def loaded_sections(objdump, coff):
    """(name, address, size) of the sections with contents that are loaded."""
    text = subprocess.run([objdump, "-h", coff], check=True, capture_output=True, text=True).stdout
    lines = text.splitlines()
    found = []
    for i, line in enumerate(lines):
        m = re.match(r"\s*\d+\s+(\S+)\s+([0-9a-f]+)\s+[0-9a-f]+\s+([0-9a-f]+)", line)
        if m and i + 1 < len(lines):
            flags = lines[i + 1]
            size, lma = int(m.group(2), 16), int(m.group(3), 16)
            if size and "LOAD" in flags and "CONTENTS" in flags:
                found.append((m.group(1), lma, size))
    return found


def start_address(objdump, coff):
    text = subprocess.run([objdump, "-f", coff], check=True, capture_output=True, text=True).stdout
    m = re.search(r"start address 0x([0-9a-f]+)", text)
    if not m:
        raise SystemExit(f"elfwrap: no start address in {coff}")
    return int(m.group(1), 16)


def build_elf(image, base, entry):
    shstr = b"\0.image\0.shstrtab\0"
    ehsize, phsize, shsize = 52, 32, 40
    data_off = ehsize + phsize
    shstr_off = data_off + len(image)
    sh_off = (shstr_off + len(shstr) + 3) & ~3
    ident = b"\x7fELF" + bytes([1, 2, 1, 0]) + bytes(8)  # ELF32, big-endian, version 1
    ehdr = ident + struct.pack(">HHIIIIIHHHHHH", 2, EM_H8_300, 1, entry, ehsize, sh_off,
                               E_H8_MACH_H8300HN, ehsize, phsize, 1, shsize, 3, 2)
    phdr = struct.pack(">IIIIIIII", 1, data_off, base, base, len(image), len(image), 7, 2)
    sh_null = bytes(shsize)
    sh_image = struct.pack(">IIIIIIIIII", 1, 1, SHF_WRITE | SHF_ALLOC | SHF_EXECINSTR, base,
                           data_off, len(image), 0, 0, 2, 0)
    sh_str = struct.pack(">IIIIIIIIII", 8, 3, 0, 0, shstr_off, len(shstr), 0, 0, 1, 0)
    pad = bytes(sh_off - shstr_off - len(shstr))
    return ehdr + phdr + image + shstr + pad + sh_null + sh_image + sh_str


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cross", default="h8300-hms-")
    ap.add_argument("coff")
    ap.add_argument("elf")
    args = ap.parse_args(argv)
    objdump, objcopy = args.cross + "objdump", args.cross + "objcopy"
    sections = loaded_sections(objdump, args.coff)
    if not sections:
        raise SystemExit(f"elfwrap: no loaded sections in {args.coff}")
    base = min(lma for _, lma, _ in sections)
    entry = start_address(objdump, args.coff)
    with tempfile.TemporaryDirectory() as tmp:
        flat = Path(tmp) / "image.bin"
        subprocess.run([objcopy, "-O", "binary", args.coff, str(flat)], check=True)
        image = flat.read_bytes()
    end = max(lma + size for _, lma, size in sections)
    if len(image) != end - base:
        raise SystemExit(f"elfwrap: flat image is {len(image)} bytes, sections span {end - base}")
    if end > 0x10000:
        raise SystemExit(f"elfwrap: image ends at 0x{end:x}, beyond normal mode's 64 KB")
    Path(args.elf).write_bytes(build_elf(image, base, entry))
    return 0


if __name__ == "__main__":
    sys.exit(main())
