#!/usr/bin/env python3
"""Writes SWIFT's virtual file for a snapshot split over several files.

sphdisk writes a multi-file snapshot (`output.files_per_snapshot`) as `snap_NNNN.k.hdf5`.
yt's SWIFT front end and swiftsimio read only the file they are given, so a part alone
gives only its share of the particles. SWIFT writes beside its parts a virtual file
`snap_NNNN.hdf5` whose datasets map the parts' (HDF5 virtual datasets); this script writes
the same with h5py, so that `yt.load` and `swiftsimio.load` of `snap_NNNN.hdf5` see every
particle. sphdisk itself reads the parts directly, and follows a virtual file to them.

The virtual file copies the first part's groups and attributes, with NumPart_ThisFile =
NumPart_Total, NumFilesPerSnapshot = 1, ThisFile = 0 and Header/Virtual = 1, as SWIFT's.
The parts are named relative to it: keep them in the same folder.

Usage: scripts/virtual_snapshot.py RUN_DIR/snap_NNNN.hdf5 [...]
       (the name without `.k`, or any part)
"""
import pathlib
import re
import sys

import h5py
import numpy as np


def parts_of(name):
    path = pathlib.Path(name)
    m = re.fullmatch(r"(.*)\.(\d+)\.hdf5", path.name)
    stem = m.group(1) if m else path.name.removesuffix(".hdf5")
    first = path.with_name(f"{stem}.0.hdf5")
    if not first.exists():
        sys.exit(f"{first}: no such file (is {name} a multi-file snapshot?)")
    with h5py.File(first, "r") as f:
        n = int(f["Header"].attrs["NumFilesPerSnapshot"][0])
    return path.with_name(f"{stem}.hdf5"), [path.with_name(f"{stem}.{k}.hdf5") for k in range(n)]


def copy_attrs(src, dst):
    for k, v in src.attrs.items():
        dst.attrs[k] = v


def write_virtual(name):
    out, parts = parts_of(name)
    files = [h5py.File(p, "r") for p in parts]
    try:
        first = files[0]
        total = first["Header"].attrs["NumPart_Total"]
        tmp = out.with_name(f".{out.name}.tmp")
        with h5py.File(tmp, "w") as v:
            for name_, g in first.items():
                if name_.startswith("PartType"):
                    continue
                copy_attrs(g, v.create_group(name_))
            h = v["Header"]
            h.attrs["NumPart_ThisFile"] = total
            h.attrs["NumFilesPerSnapshot"] = np.array([1], dtype=np.int32)
            h.attrs["ThisFile"] = np.array([0], dtype=np.int32)
            h.attrs["Virtual"] = np.array([1], dtype=np.int32)
            groups = sorted({g for f in files for g in f if g.startswith("PartType")})
            for gname in groups:
                have = [f for f in files if gname in f]
                out_g = v.create_group(gname)
                copy_attrs(have[0][gname], out_g)
                for dname, d0 in have[0][gname].items():
                    counts = [f[gname][dname].shape[0] for f in have]
                    shape = (sum(counts),) + d0.shape[1:]
                    layout = h5py.VirtualLayout(shape=shape, dtype=d0.dtype)
                    start = 0
                    for f, c in zip(have, counts):
                        # The part's name relative to the virtual file (same folder).
                        src = h5py.VirtualSource(pathlib.Path(f.filename).name,
                                                 f"{gname}/{dname}", shape=(c,) + d0.shape[1:])
                        layout[start:start + c] = src
                        start += c
                    ds = out_g.create_virtual_dataset(dname, layout)
                    copy_attrs(d0, ds)
        tmp.replace(out)
    finally:
        for f in files:
            f.close()
    return out, len(parts)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for arg in sys.argv[1:]:
        out, n = write_virtual(arg)
        print(f"{out}: virtual snapshot of {n} files")
