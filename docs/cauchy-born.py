#!/usr/bin/env python3
"""Young's modulus along a lattice axis of `Mesh::cuboid`'s mirrored Kuhn lattice, per unit `s E`,
for the spring-like models (Cauchy-Born: a uniform strain, each spring of direction n and volume
share w storing ½ s E w (n·εn)², uniaxial stress with free sides). Prints the constants `s` that
make it `E`: springs 31/7 (3D) and 5/2 (2D), centroid springs 29/10 and 109/68.

    pip install numpy && python3 docs/cauchy-born.py
"""
import itertools
from fractions import Fraction

import numpy as np


def stiffness(directions, dim):
    """Voigt matrix of Σ w n⊗n⊗n⊗n."""
    idx = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)] if dim == 3 else [(0, 0), (1, 1), (0, 1)]
    c = np.zeros((len(idx), len(idx)))
    for n, w in directions:
        for a, (i, j) in enumerate(idx):
            for b, (k, l) in enumerate(idx):
                c[a, b] += w * n[i] * n[j] * n[k] * n[l]
    return c


def cells(dim):
    """The Kuhn simplices of a unit cube (one per axis order), in all 2^dim mirror images."""
    out = []
    for signs in itertools.product([1.0, -1.0], repeat=dim):
        s = np.array(signs)
        for order in itertools.permutations(range(dim)):
            v = [np.zeros(dim)]
            for axis in order:
                p = v[-1].copy()
                p[axis] += 1.0
                v.append(p)
            out.append([p * s for p in v])
    return out


def volume(t, dim):
    return abs(np.linalg.det(np.array([t[i] - t[0] for i in range(1, dim + 1)]))) / (6 if dim == 3 else 2)


for dim in (3, 2):
    simplices = cells(dim)
    total = sum(volume(t, dim) for t in simplices)
    edges, centroid = [], []
    for t in simplices:
        v, n = volume(t, dim), len(t)
        pairs = n * (n - 1) // 2
        for a, b in itertools.combinations(range(n), 2):
            d = t[b] - t[a]
            edges.append((d / np.linalg.norm(d), v / pairs / total))
        c = sum(t) / n
        for p in t:
            d = p - c
            centroid.append((d / np.linalg.norm(d), v / n / total))
    for name, c in [("springs", stiffness(edges, dim)),
                    ("centroid springs", stiffness(edges, dim) + stiffness(centroid, dim))]:
        young = 1.0 / np.linalg.inv(c)[0, 0]
        print(f"{dim}D {name}: E = {Fraction(young).limit_denominator(1000)} s E, "
              f"s = {Fraction(1 / young).limit_denominator(1000)}")
