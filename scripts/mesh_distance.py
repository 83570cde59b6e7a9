#!/usr/bin/python3
"""How far one mesh's vertices are from another's (two runs' mesh.ply, e.g. two builds' on a clip
without surface ground truth). For each vertex of A: the distance to the nearest vertex of B,
searched within one cell of size H around it (2 H when none is that close).

  ./scripts/mesh_distance.py A.ply B.ply H

Prints the vertex counts, the median and p90 of those distances and the share of A's vertices
at least H from every vertex of B. Reads binary little-endian PLY (vitamin_e_run's mesh.ply).
"""
import argparse
import collections
import math
import struct
import sys

TYPES = {"float": "f", "float32": "f", "double": "d", "uchar": "B", "uint8": "B", "int": "i", "int32": "i"}


def read_vertices(path):
    with open(path, "rb") as f:
        n, props, fmt, element = 0, [], None, None
        while True:
            line = f.readline()
            if not line:
                sys.exit(f"mesh_distance: {path}: no end_header")
            words = line.decode("ascii", "replace").split()
            if not words:
                continue
            if words[0] == "format":
                fmt = words[1]
            elif words[0] == "element":
                element = words[1]
                if element == "vertex":
                    n = int(words[2])
            elif words[0] == "property" and element == "vertex":
                if words[1] not in TYPES:
                    sys.exit(f"mesh_distance: {path}: vertex property type {words[1]} not handled")
                props.append(TYPES[words[1]])
            elif words[0] == "end_header":
                break
        if fmt != "binary_little_endian":
            sys.exit(f"mesh_distance: {path}: format {fmt} not handled (binary_little_endian only)")
        st = struct.Struct("<" + "".join(props))
        data = f.read(st.size * n)
        if len(data) < st.size * n:
            sys.exit(f"mesh_distance: {path}: {n} vertices announced, the file is shorter")
        return [st.unpack_from(data, i * st.size)[:3] for i in range(n)]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("a", help="the mesh whose vertices are measured (PLY)")
    parser.add_argument("b", help="the mesh they are measured against (PLY)")
    parser.add_argument("h", type=float, help="cell size and threshold (the mesh's units, e.g. a voxel)")
    args = parser.parse_args()
    a, b, h = read_vertices(args.a), read_vertices(args.b), args.h
    if not a or not b or not h > 0:
        sys.exit("mesh_distance: both meshes need vertices and H must be > 0")
    cell = lambda p: tuple(int(math.floor(c / h)) for c in p)
    grid = collections.defaultdict(list)
    for q in b:
        grid[cell(q)].append(q)
    d = []
    for p in a:
        k, best = cell(p), 2 * h
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for q in grid.get((k[0] + dx, k[1] + dy, k[2] + dz), ()):
                        best = min(best, math.dist(p, q))
        d.append(best)
    d.sort()
    far = sum(x >= h for x in d) / len(d)
    print(f"{len(a)} vs {len(b)} vertices; distance to the other mesh: median {d[len(d) // 2]:.5f} "
          f"p90 {d[int(len(d) * 0.9)]:.5f}; share >= {h:g}: {far:.4f}")


if __name__ == "__main__":
    main()
