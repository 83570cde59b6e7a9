#!/usr/bin/python3
"""Offscreen render of a triangle mesh PLY (as written by fusion::saveMeshPly) to PNG.

    scripts/render_mesh.py MESH.ply OUT.png [--size 1200x800] [--azimuth DEG]
                           [--elevation DEG] [--distance X] [--up z|-y|...]

Perspective camera looking at the centre of the mesh's bounding box from the
given azimuth / elevation around the up axis; back faces are culled (faces are
counter-clockwise seen from free space), so a room seen from outside shows its
inside. Painter's algorithm (far to near) with OpenCV polygon filling, Lambert
shading from a light above the camera, colour by height; rendered at twice the
size and downsampled. Needs numpy and OpenCV (python3-opencv).
"""
import argparse
import sys

import cv2
import numpy as np


def read_ply(path):
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline()
            if not line:
                sys.exit("%s: no end_header" % path)
            line = line.decode("ascii").strip()
            header.append(line)
            if line == "end_header":
                break
        fmt = next(l.split()[1] for l in header if l.startswith("format"))
        nv = int(next(l.split()[2] for l in header if l.startswith("element vertex")))
        nf = int(next(l.split()[2] for l in header if l.startswith("element face")))
        props = [l.split()[2] for l in header if l.startswith("property float")]
        if fmt == "ascii":
            data = f.read().decode("ascii").split()
            vals = np.array(data[: nv * len(props)], dtype=np.float64).reshape(nv, len(props))
            rest = np.array(data[nv * len(props):], dtype=np.int64).reshape(nf, 4)
            faces = rest[:, 1:]
        else:
            vals = np.frombuffer(f.read(4 * nv * len(props)), dtype="<f4").reshape(nv, len(props))
            rec = np.frombuffer(f.read(13 * nf), dtype=np.dtype([("n", "u1"), ("i", "<i4", (3,))]))
            if nf and not np.all(rec["n"] == 3):
                sys.exit("%s: only triangles are supported" % path)
            faces = rec["i"].astype(np.int64)
    xyz = vals[:, [props.index("x"), props.index("y"), props.index("z")]].astype(np.float64)
    return xyz, faces


def axis_vector(name):
    sign = -1.0 if name.startswith("-") else 1.0
    v = np.zeros(3)
    v["xyz".index(name[-1])] = sign
    return v


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("out")
    ap.add_argument("--size", default="1200x800")
    ap.add_argument("--azimuth", type=float, default=-60.0)
    ap.add_argument("--elevation", type=float, default=55.0)
    ap.add_argument("--distance", type=float, default=1.6, help="in bounding-box diagonals")
    ap.add_argument("--fov", type=float, default=40.0, help="horizontal field of view [deg]")
    ap.add_argument("--up", default="z")
    a = ap.parse_args()
    W, H = (int(x) for x in a.size.split("x"))
    ss = 2  # supersampling
    xyz, faces = read_ply(a.mesh)
    if len(faces) == 0:
        sys.exit("%s: no faces" % a.mesh)
    up = axis_vector(a.up)
    lo, hi = xyz.min(0), xyz.max(0)
    centre, diag = 0.5 * (lo + hi), np.linalg.norm(hi - lo)
    # Camera position from azimuth/elevation around `up`.
    ref = np.array([1.0, 0.0, 0.0]) if abs(up[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(up, ref)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(up, e1)
    az, el = np.radians(a.azimuth), np.radians(a.elevation)
    direction = np.cos(el) * (np.cos(az) * e1 + np.sin(az) * e2) + np.sin(el) * up
    eye = centre + a.distance * diag * direction
    fwd = centre - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    down = np.cross(fwd, right)
    R = np.stack([right, down, fwd])  # world -> camera (optical)
    f = 0.5 * W * ss / np.tan(0.5 * np.radians(a.fov))
    p_c = (xyz - eye) @ R.T
    uv = np.stack([f * p_c[:, 0] / p_c[:, 2] + 0.5 * W * ss, f * p_c[:, 1] / p_c[:, 2] + 0.5 * H * ss], axis=1)

    A, B, C = xyz[faces[:, 0]], xyz[faces[:, 1]], xyz[faces[:, 2]]
    n = np.cross(B - A, C - A)
    nn = np.linalg.norm(n, axis=1)
    ok = nn > 0
    n[ok] /= nn[ok, None]
    centroid = (A + B + C) / 3.0
    facing = np.einsum("ij,ij->i", n, eye - centroid) > 0.0
    in_front = (p_c[faces].min(axis=1)[:, 2] > 1e-3)
    keep = ok & facing & in_front
    light = -fwd + 0.8 * up
    light /= np.linalg.norm(light)
    shade = 0.25 + 0.75 * np.clip(n @ light, 0.0, 1.0)
    h = centroid @ up
    t = np.clip((h - (lo @ up if up.sum() > 0 else h.min())) / max(1e-9, np.ptp(h)), 0.0, 1.0)
    lut = cv2.applyColorMap(np.arange(256, dtype=np.uint8).reshape(-1, 1), cv2.COLORMAP_VIRIDIS).reshape(256, 3)
    base = 0.55 * lut[(t * 255).astype(int)].astype(np.float64) + 0.45 * 235.0
    colour = np.clip(base * shade[:, None], 0, 255).astype(np.uint8)
    depth = p_c[faces, 2].mean(axis=1)
    order = np.nonzero(keep)[0]
    order = order[np.argsort(-depth[order])]
    img = np.full((H * ss, W * ss, 3), 255, np.uint8)
    pts = np.round(uv[faces] * 16).astype(np.int32)  # 4 fractional bits
    for i in order:
        cv2.fillConvexPoly(img, pts[i], colour[i].tolist(), lineType=cv2.LINE_8, shift=4)
    img = cv2.resize(img, (W, H), interpolation=cv2.INTER_AREA)
    if not cv2.imwrite(a.out, img):
        sys.exit("cannot write %s" % a.out)
    print("%s: %d of %d faces drawn, %dx%d" % (a.out, len(order), len(faces), W, H))


if __name__ == "__main__":
    main()
