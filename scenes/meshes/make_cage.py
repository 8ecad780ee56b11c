"""Writes cage.obj: a hollow cube (7x7x7 voxels, walls one voxel thick) with four square windows
in each face, as the boundary of the voxel set.  The result is a closed, consistently outward-wound
2-manifold of genus 23 (the classic picture of a point light inside an object with holes).

Run `python make_cage.py` to regenerate; the file is ours (CC0).
"""

import itertools
from pathlib import Path

import numpy as np

N = 7
WINDOWS = [(2, 2), (2, 4), (4, 2), (4, 4)]  # cells removed from every face (never edge-adjacent)


def cells() -> np.ndarray:
    filled = np.zeros((N, N, N), bool)
    filled[[0, -1]] = filled[:, [0, -1]] = filled[:, :, [0, -1]] = True
    for axis, side in itertools.product(range(3), (0, N - 1)):
        for i, j in WINDOWS:
            idx = [i, j]
            idx.insert(axis, side)
            filled[tuple(idx)] = False
    return filled


def boundary(filled: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quads between filled and empty cells, wound counter-clockwise seen from outside."""
    verts: dict[tuple[int, int, int], int] = {}
    faces = []

    def vid(p):
        return verts.setdefault(p, len(verts))

    padded = np.pad(filled, 1)
    for x, y, z in zip(*np.nonzero(filled)):
        for axis, step in itertools.product(range(3), (-1, 1)):
            n = [x + 1, y + 1, z + 1]
            n[axis] += step
            if padded[tuple(n)]:
                continue
            u, v = (axis + 1) % 3, (axis + 2) % 3  # u x v = +axis
            if step < 0:
                u, v = v, u  # keep the winding outward on the negative side
            base = [x, y, z]
            if step > 0:
                base[axis] += 1
            corners = []
            for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                c = list(base)
                c[u] += du
                c[v] += dv
                corners.append(vid(tuple(c)))
            faces += [(corners[0], corners[1], corners[2]), (corners[0], corners[2], corners[3])]
    v = np.array(sorted(verts, key=verts.get), float) / N - 0.5  # unit cube centred on 0
    return v, np.array(faces)


if __name__ == "__main__":
    v, f = boundary(cells())
    lines = ["# cage.obj: hollow cube with 24 windows, made by make_cage.py (CC0)"]
    lines += [f"v {a:.6g} {b:.6g} {c:.6g}" for a, b, c in v]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f]
    Path(__file__).with_name("cage.obj").write_text("\n".join(lines) + "\n")
    print(f"{len(v)} vertices, {len(f)} triangles")
