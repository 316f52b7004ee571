"""Planar geometry of the checks: the convex hull of points on the floor and a point's signed
distance to it (m, > 0 inside), for the measured ZMP against the soles' outlines and the CoM
against the soles' contact points."""

from __future__ import annotations

import math

import numpy as np


def convex_hull(points: np.ndarray) -> np.ndarray:
    """Convex hull (counter-clockwise) of 2-D points (monotone chain)."""
    pts = sorted(set((round(float(x), 9), round(float(y), 9)) for x, y in points))
    if len(pts) < 3:
        return np.array(pts)
    chain = []
    for half in (pts, pts[::-1]):
        start = len(chain)
        for x, y in half:
            while len(chain) >= start + 2:
                (ox, oy), (ax, ay) = chain[-2], chain[-1]
                if (ax - ox) * (y - oy) - (ay - oy) * (x - ox) > 0:
                    break
                chain.pop()
            chain.append((x, y))
        chain.pop()
    return np.array(chain)


def signed_distance(hull: np.ndarray, p: np.ndarray) -> float:
    """Signed distance of ``p`` to the hull's boundary (> 0 inside); -inf without a hull. A
    point or a segment has no inside."""
    if len(hull) == 0:
        return -math.inf
    if len(hull) == 1:
        return -float(np.linalg.norm(p - hull[0]))
    edge = np.roll(hull, -1, axis=0) - hull
    rel = p - hull
    along = np.clip(np.einsum("ij,ij->i", rel, edge) / np.maximum(np.einsum("ij,ij->i", edge, edge), 1e-18), 0.0, 1.0)
    dist = float(np.min(np.hypot(*(rel - along[:, None] * edge).T)))
    inside = len(hull) >= 3 and bool(np.all(edge[:, 0] * rel[:, 1] - edge[:, 1] * rel[:, 0] >= 0))
    return dist if inside else -dist
