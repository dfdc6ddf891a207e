#!/usr/bin/python3
"""Reader for pfflip frames (HDF5 files written by PffIOWriteFrame; layout in docs/file-format.md).

Library use:
    from pff_frame import Frame
    with Frame("out/frame_0010.h5") as f:
        print(f.time, f.step, f.nactive)
        phi = f.block_values("phi", 0)        # block 0 in Morton order, array [k, j, i] of n^3
        slab = f.finest_slice("phi", axis=2)  # a plane on the finest lattice, coarse cells repeated

Command line:
    pff_frame.py --summary frame.h5   # block count, channels and min / max / sum of each dataset
    pff_frame.py --check frame.h5     # checks the layout and the XDMF sidecar; exit status 1 on a fault

Frames written by PffIOWriteFrameParticles and checkpoints also hold /particles (count attribute, x, v,
id, type, level, flags); --check verifies its shapes and the sidecar's Polyvertex particle grid.

Needs only h5py and numpy (Debian python3-h5py, python3-numpy).
"""
import argparse
import os
import sys
import xml.dom.minidom

import h5py
import numpy as np

FORMAT = "pfflip-frame"
FORMAT_VERSION = 1


def _str(value):
    """HDF5 string attributes arrive as bytes (fixed length) or str (variable length)."""
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.ndarray) and value.shape == ():
        return _str(value[()])
    return str(value)


def morton_key(i, j, k):
    """Morton (Z-order) key with x in the lowest bit, as PffMortonEncode in include/pff/core.h."""

    def spread(v):
        v = np.asarray(v, dtype=np.uint64) & np.uint64(0x1FFFFF)
        for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF), (8, 0x100F00F00F00F00F),
                            (4, 0x10C30C30C30C30C3), (2, 0x1249249249249249)):
            v = (v | (v << np.uint64(shift))) & np.uint64(mask)
        return v

    return spread(i) | (spread(j) << np.uint64(1)) | (spread(k) << np.uint64(2))


class FrameError(Exception):
    pass


class Frame:
    """One frame. Blocks are indexed by their Morton position p = 0 .. nactive-1."""

    def __init__(self, path):
        self.path = path
        self.h5 = h5py.File(path, "r")
        a = self.h5.attrs
        if _str(a.get("format", "")) != FORMAT:
            raise FrameError(f"{path}: not a pfflip frame (format attribute {_str(a.get('format', '(missing)'))!r})")
        self.format_version = int(a["format_version"])
        if self.format_version > FORMAT_VERSION:
            raise FrameError(f"{path}: format_version {self.format_version} is newer than this reader ({FORMAT_VERSION})")
        self.time = float(a["time"])
        self.step = int(a["step"])
        self.scene = _str(a.get("scene", ""))
        self.options = _str(a.get("options", ""))
        self.git_revision = _str(a.get("git_revision", ""))
        self.versions = _str(a.get("versions", ""))
        self.mpi_ranks = int(a.get("mpi_ranks", 0))
        self.omp_threads = int(a.get("omp_threads", 0))

        g = self.h5["grid"]
        self.block_size = int(g.attrs["block_size"])
        self.levels = int(g.attrs["levels"])
        self.origin = np.asarray(g.attrs["origin"], dtype=np.float64)
        self.h0 = float(g.attrs["h0"])
        self.periodic = np.asarray(g.attrs["periodic"], dtype=bool)
        self.raster = np.asarray(g.attrs["raster"], dtype=np.int64)  # nb x, y, z
        self.level_map = g["level"][...].reshape(self.raster[::-1])  # [kb, jb, ib], -1 inactive

        b = self.h5["blocks"]
        self.gid = b["gid"][...]
        self.block_level = b["level"][...]
        self.owner = b["owner"][...]
        self.block_origin = b["origin"][...]
        self.offset = b["offset"][...]
        self.nactive = len(self.gid)
        self.block_n = self.block_size >> self.block_level
        nb = self.raster
        self.block_ijk = np.stack([self.gid % nb[0], (self.gid // nb[0]) % nb[1], self.gid // (nb[0] * nb[1])], axis=1)
        self.ncells = int(self.offset[-1] + self.block_n[-1] ** 3) if self.nactive else 0

    def close(self):
        self.h5.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def datasets(self):
        """Field datasets as (name, kind, component, channel), in file order."""
        out = []
        for name, d in self.h5["fields"].items():
            out.append((name, _str(d.attrs.get("kind", "cell")), int(d.attrs.get("component", 0)),
                        _str(d.attrs.get("channel", name))))
        return out

    def channels(self):
        """{channel: (kind, [dataset names])}."""
        ch = {}
        for name, kind, _, channel in self.datasets():
            ch.setdefault(channel, (kind, []))[1].append(name)
        return ch

    def field(self, name):
        """The whole 1-D dataset /fields/<name> (all blocks, Morton order)."""
        if name not in self.h5["fields"]:
            raise FrameError(f"{self.path}: no dataset /fields/{name}; have {', '.join(self.h5['fields'])}")
        return self.h5["fields"][name][...]

    def block_values(self, name, p, data=None):
        """Values of block p as an array [k, j, i] of n^3 (pass data=field(name) when reading many blocks)."""
        n = int(self.block_n[p])
        src = data if data is not None else self.h5["fields"][name]
        o = int(self.offset[p])
        return np.asarray(src[o:o + n ** 3]).reshape(n, n, n)

    def finest_slice(self, name, axis=2, index=None):
        """Plane `index` (default: the middle layer) normal to `axis` (0 = x, 1 = y, 2 = z) on the finest
        lattice. Coarse cells are repeated 2^level times; inactive blocks are NaN. Returns the 2-D array
        (rows = the slower remaining axis) and the world extent [lo, hi] of its two axes."""
        n0 = self.block_size
        cells = self.raster * n0
        if index is None:
            index = int(cells[axis] // 2)
        if not 0 <= index < cells[axis]:
            raise FrameError(f"slice index {index} outside [0, {cells[axis]})")
        a, b = [d for d in range(3) if d != axis]  # image columns along a, rows along b
        img = np.full((cells[b], cells[a]), np.nan, dtype=np.float32)
        data = self.field(name)
        ib = index // n0
        for p in np.nonzero(self.block_ijk[:, axis] == ib)[0]:
            f = 1 << int(self.block_level[p])
            v = self.block_values(name, p, data)  # [k, j, i]
            c = (index - ib * n0) // f
            plane = np.take(v, c, axis=2 - axis)  # remaining axes in [slow, fast] = [b, a] order
            plane = np.repeat(np.repeat(plane, f, axis=0), f, axis=1)
            ijk = self.block_ijk[p]
            img[ijk[b] * n0:(ijk[b] + 1) * n0, ijk[a] * n0:(ijk[a] + 1) * n0] = plane
        lo = self.origin
        hi = self.origin + cells * self.h0
        return img, (a, b), (lo[a], hi[a], lo[b], hi[b])


def summary(f):
    print(f"{f.path}: {FORMAT} v{f.format_version}, scene {f.scene!r}, step {f.step}, time {f.time:.10g}")
    print(f"written on {f.mpi_ranks} ranks x {f.omp_threads} threads, revision {f.git_revision}")
    nb = f.raster
    counts = np.bincount(f.block_level, minlength=f.levels)
    print(f"raster {nb[0]}x{nb[1]}x{nb[2]} blocks of {f.block_size}^3, {f.levels} levels, h0 {f.h0:.6g}, "
          f"origin {f.origin[0]:.6g} {f.origin[1]:.6g} {f.origin[2]:.6g}")
    print(f"blocks {f.nactive} active of {int(np.prod(nb))} (per level: {' '.join(str(c) for c in counts)}), "
          f"cells {f.ncells}")
    print(f"{'dataset':<24} {'kind':<5} {'comp':>4} {'min':>17} {'max':>17} {'sum':>17}")
    for name, kind, comp, _ in f.datasets():
        v = f.field(name)
        print(f"{name:<24} {kind:<5} {comp:>4} {v.min():17.9e} {v.max():17.9e} {v.sum(dtype=np.float64):17.9e}")
    n = particle_count(f)
    if n is not None:
        types = np.bincount(f.h5["particles/type"][...], minlength=2) if n > 0 else np.zeros(2, np.int64)
        print(f"particles {n} (per type: {' '.join(str(int(c)) for c in types)}), x {f.h5['particles/x'].dtype}")


def check(f):
    """Consistency of the layout (docs/file-format.md) and of the XDMF sidecar; returns a list of faults."""
    faults = []
    n = f.block_n.astype(np.int64)
    expect = np.concatenate([[0], np.cumsum(n ** 3)[:-1]]) if f.nactive else np.zeros(0, np.int64)
    if not np.array_equal(f.offset, expect):
        faults.append("/blocks/offset is not the prefix sum of n^3")
    active = np.flatnonzero(f.level_map.reshape(-1) >= 0)
    if not np.array_equal(np.sort(f.gid), active):
        faults.append("/blocks/gid is not the set of active blocks of /grid/level")
    keys = morton_key(*f.block_ijk.T)
    if np.any(keys[1:] <= keys[:-1]):
        faults.append("/blocks/gid is not in increasing Morton order")
    if not np.array_equal(f.level_map.reshape(-1)[f.gid], f.block_level):
        faults.append("/blocks/level differs from /grid/level")
    lo = f.origin + f.block_ijk * (f.block_size * f.h0)
    if not np.allclose(f.block_origin, lo, rtol=0, atol=1e-12 * max(1.0, np.abs(lo).max(initial=1.0))):
        faults.append("/blocks/origin differs from origin + ijk * block_size * h0")
    if np.any(f.owner < 0) or np.any(f.owner >= max(f.mpi_ranks, 1)):
        faults.append("/blocks/owner outside [0, mpi_ranks)")
    for name, kind, comp, channel in f.datasets():
        d = f.h5["fields"][name]
        if d.shape != (f.ncells,):
            faults.append(f"/fields/{name} has shape {d.shape}, expected ({f.ncells},)")
        if kind not in ("cell", "face") or (kind == "cell" and comp != 0) or (kind == "face" and not 0 <= comp < 3):
            faults.append(f"/fields/{name}: kind {kind!r} component {comp}")
    faults += check_particles(f)
    if not int(f.h5.attrs.get("checkpoint", 0)):  # checkpoints have no sidecar
        faults += check_xdmf(f)
    return faults


PARTICLE_COLUMNS = {"x": 3, "v": 3, "id": 0, "type": 0, "level": 0, "flags": 0}


def particle_count(f):
    """Rows of /particles, or None when the file has no particles."""
    if "particles" not in f.h5:
        return None
    return int(f.h5["particles"].attrs.get("count", -1))


def check_particles(f):
    n = particle_count(f)
    if n is None:
        return []
    if n < 0:
        return ["/particles has no count attribute"]
    g = f.h5["particles"]
    faults = []
    for name, ncol in PARTICLE_COLUMNS.items():
        shape = (n, ncol) if ncol else (n,)
        if name not in g:
            faults.append(f"/particles/{name} missing")
        elif g[name].shape != shape:
            faults.append(f"/particles/{name} has shape {g[name].shape}, expected {shape}")
    return faults


def check_xdmf(f):
    base, _ = os.path.splitext(f.path)
    xmf = base + ".xmf" if f.path.endswith(".h5") else f.path + ".xmf"
    if not os.path.exists(xmf):
        return [f"{xmf}: missing"]
    try:
        doc = xml.dom.minidom.parse(xmf)
    except Exception as e:  # any parse failure is the fault we report
        return [f"{xmf}: not well-formed XML: {e}"]
    uniform = [g for g in doc.getElementsByTagName("Grid") if g.getAttribute("GridType") == "Uniform"]
    grids = [g for g in uniform if g.getAttribute("Name") != "particles"]
    faults = check_xdmf_particles(f, xmf, [g for g in uniform if g.getAttribute("Name") == "particles"])
    if len(grids) != f.nactive:
        return faults + [f"{xmf}: {len(grids)} uniform grids, the frame has {f.nactive} blocks"]
    h5name = os.path.basename(f.path)
    names = {name for name, *_ in f.datasets()}
    for p, g in enumerate(grids):
        n = int(f.block_n[p])
        topo = g.getElementsByTagName("Topology")[0].getAttribute("Dimensions").split()
        if [int(t) for t in topo] != [n + 1] * 3:
            faults.append(f"{xmf}: block {p} topology {topo}")
        org = [float(t) for t in g.getElementsByTagName("Geometry")[0].getElementsByTagName("DataItem")[0]
               .firstChild.data.split()]
        if not np.allclose(org[::-1], f.block_origin[p]):
            faults.append(f"{xmf}: block {p} origin {org}")
        seen = set()
        for at in g.getElementsByTagName("Attribute"):
            items = at.getElementsByTagName("DataItem")
            start, stride, count = (int(t) for t in items[1].firstChild.data.split())
            ref = items[2].firstChild.data.strip()
            fname, _, dpath = ref.partition(":")
            dname = dpath.rsplit("/", 1)[-1]
            seen.add(dname)
            if fname != h5name or dpath != "/fields/" + dname or dname not in names:
                faults.append(f"{xmf}: block {p} refers to {ref}")
            if (start, stride, count) != (int(f.offset[p]), 1, n ** 3):
                faults.append(f"{xmf}: block {p} {dname} hyperslab {start} {stride} {count}")
        if seen != names:
            faults.append(f"{xmf}: block {p} lists {sorted(seen)}, the frame has {sorted(names)}")
        if len(faults) > 10:
            break
    return faults


def check_xdmf_particles(f, xmf, grids):
    """The particle grid: a Polyvertex of count nodes over /particles/x (none when there are no particles)."""
    n = particle_count(f) or 0
    if n == 0:
        return [f"{xmf}: a particle grid but the frame has no particles"] if grids else []
    if len(grids) != 1:
        return [f"{xmf}: {len(grids)} particle grids, expected 1 for {n} particles"]
    g = grids[0]
    topo = g.getElementsByTagName("Topology")[0]
    faults = []
    if topo.getAttribute("TopologyType") != "Polyvertex" or topo.getAttribute("NumberOfElements") != str(n):
        faults.append(f"{xmf}: particle topology is not a Polyvertex of {n} elements")
    h5name = os.path.basename(f.path)
    refs = {d.firstChild.data.strip() for d in g.getElementsByTagName("DataItem")}
    for name in ("x", "v", "type"):
        if f"{h5name}:/particles/{name}" not in refs:
            faults.append(f"{xmf}: the particle grid does not refer to {h5name}:/particles/{name}")
    return faults


def main(argv=None):
    ap = argparse.ArgumentParser(description="Summarise or check a pfflip HDF5 frame.")
    ap.add_argument("frame", help="frame file (.h5)")
    ap.add_argument("--summary", action="store_true", help="print blocks, channels and min/max/sum of each dataset")
    ap.add_argument("--check", action="store_true", help="check the layout and the XDMF sidecar (exit 1 on a fault)")
    args = ap.parse_args(argv)
    if not os.path.exists(args.frame):
        print(f"cannot open frame {args.frame}: no such file", file=sys.stderr)
        return 1
    try:
        with Frame(args.frame) as f:
            if args.summary or not args.check:
                summary(f)
            if args.check:
                faults = check(f)
                for msg in faults:
                    print("FAULT " + msg, file=sys.stderr)
                if faults:
                    return 1
                print(f"{args.frame}: layout and XDMF sidecar consistent")
    except (FrameError, KeyError, OSError) as e:
        print(f"{args.frame}: {e}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
