#!/usr/bin/env python3
"""Writes torus-knot.obj (run from this directory): a trefoil, the (2, 3) torus knot, as a
closed tube, the game asset of `examples/asset.rs`. Centre line ((2 + cos 3t) cos 2t,
sin 3t, (2 + cos 3t) sin 2t) times 0.08 m, tube radius 0.04 m, 240 rings of 16 vertices,
frames by parallel transport (closed up by a twist spread along the tube)."""
import math

S, A, N, M = 0.08, 0.5, 240, 16


def centre(t):
    r = 2 + math.cos(3 * t)
    return [r * math.cos(2 * t), math.sin(3 * t), r * math.sin(2 * t)]


def sub(a, b): return [a[i] - b[i] for i in range(3)]
def dot(a, b): return sum(a[i] * b[i] for i in range(3))
def cross(a, b): return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
def unit(a):
    l = math.sqrt(dot(a, a))
    return [x / l for x in a]


ts = [2 * math.pi * i / N for i in range(N)]
pts = [centre(t) for t in ts]
tangents = [unit(sub(pts[(i + 1) % N], pts[i - 1])) for i in range(N)]
# Parallel transport of a normal around the loop.
n = unit(cross(tangents[0], [0, 1, 0]))
normals = []
for i in range(N):
    t = tangents[i]
    n = unit(sub(n, [dot(n, t) * x for x in t]))
    normals.append(n)
# The frame comes back turned by some angle: spread its correction along the tube.
end = unit(sub(n, [dot(n, tangents[0]) * x for x in tangents[0]]))
b0 = cross(tangents[0], normals[0])
twist = math.atan2(dot(end, b0), dot(end, normals[0]))
verts = []
for i in range(N):
    t, n = tangents[i], normals[i]
    b = cross(t, n)
    for j in range(M):
        a = 2 * math.pi * j / M - twist * i / N
        off = [A * (math.cos(a) * n[k] + math.sin(a) * b[k]) for k in range(3)]
        verts.append([S * (pts[i][k] + off[k]) for k in range(3)])
faces = []
for i in range(N):
    for j in range(M):
        v = lambda i, j: (i % N) * M + (j % M) + 1
        faces += [(v(i, j), v(i + 1, j), v(i + 1, j + 1)), (v(i, j), v(i + 1, j + 1), v(i, j + 1))]
with open("torus-knot.obj", "w") as f:
    f.write("# A trefoil knot tube, 0.08 m scale: written by make_torus_knot.py\no torus_knot\n")
    for p in verts:
        f.write("v %.5f %.5f %.5f\n" % tuple(p))
    for t in faces:
        f.write("f %d %d %d\n" % t)
