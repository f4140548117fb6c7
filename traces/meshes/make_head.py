#!/usr/bin/env python3
"""Writes traces/meshes/head.obj: a low-poly head of many creases for the leak test.

An icosphere subdivided three times (642 vertices, 1280 triangles) stretched to a head's
ellipsoid, with features pushed along each vertex's direction d by Gaussian bumps of the
angle to a feature's direction: a nose, a brow ridge, eye sockets, cheekbones, ears, a
chin, a mouth, nostrils and grooves behind the ears, some with a pointed profile
(exp(-angle / width)) that leaves sharp ridges. Then each vertex's radius is scaled by
1 + AMP * (u - 0.5), u from Python's random module seeded with SEED. Two eyeballs
(icospheres of level 1, 80 triangles each) are separate shells sunk into the sockets, so
they cut through the face. Auto-smoothed at 35 degrees (traces/head_creased.json), 174 of
the head's 1 920 edges are creases, at angles up to 95 degrees: creases of many angles,
short and long, corners where several meet, creases ending inside smooth regions; and
where the eyes cut the face, the curved patches cross where the flat triangles do not.

    python3 traces/meshes/make_head.py 3 7 0.08 > traces/meshes/head.obj
"""
import math, random, sys


def icosphere(level):
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(level):
        cache, nf = {}, []

        def mid(a, b):
            k = (min(a, b), max(a, b))
            if k not in cache:
                p = [(v[a][i] + v[b][i]) / 2 for i in range(3)]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                cache[k] = len(v) - 1
            return cache[k]

        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return v, f


def unit(p):
    n = math.sqrt(sum(x * x for x in p))
    return tuple(x / n for x in p)


# (direction, height, angular width [radians], profile): smooth bumps are Gaussian in the
# angle, pointed ones fall off linearly-exponentially and leave a ridge at their tip.
FEATURES = [
    (unit((0, -0.05, 1)), 0.32, 0.16, "pointed"),   # nose
    (unit((0, 0.3, 1)), 0.10, 0.22, "smooth"),      # brow
    (unit((0.35, 0.18, 1)), -0.14, 0.12, "smooth"),  # eye sockets
    (unit((-0.35, 0.18, 1)), -0.14, 0.12, "smooth"),
    (unit((0.6, -0.1, 0.8)), 0.08, 0.15, "pointed"),  # cheekbones
    (unit((-0.6, -0.1, 0.8)), 0.08, 0.15, "pointed"),
    (unit((1, 0.05, -0.1)), 0.22, 0.13, "pointed"),  # ears
    (unit((-1, 0.05, -0.1)), 0.22, 0.13, "pointed"),
    (unit((0, -0.75, 0.65)), 0.16, 0.2, "pointed"),  # chin
    (unit((0, -0.3, 1)), -0.06, 0.08, "smooth"),     # under the nose
    (unit((0, -0.45, 1)), -0.22, 0.06, "pointed"),   # mouth
    (unit((0.09, -0.12, 1)), -0.12, 0.035, "pointed"),  # nostrils
    (unit((-0.09, -0.12, 1)), -0.12, 0.035, "pointed"),
    (unit((0.92, 0.05, -0.4)), -0.18, 0.07, "pointed"),  # behind the ears
    (unit((-0.92, 0.05, -0.4)), -0.18, 0.07, "pointed"),
]


def height(d):
    h = 0.0
    for f, amount, width, profile in FEATURES:
        angle = math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(d, f)))))
        if profile == "smooth":
            h += amount * math.exp(-(angle / width) ** 2)
        else:
            h += amount * math.exp(-angle / width)
    return h


level, seed, amp = int(sys.argv[1]), int(sys.argv[2]), float(sys.argv[3])
random.seed(seed)
v, f = icosphere(level)
shape = (0.78, 1.0, 0.88)
out = []
for d in v:
    r = (1 + height(d)) * (1 + amp * (random.random() - 0.5))
    out.append(tuple(r * s * c for s, c in zip(shape, d)))
faces = list(f)
# Two eyeballs, separate closed shells (icospheres of level 1) sunk into the sockets so
# that they cut through the face: the curved patches of face and eye cross where the flat
# triangles do not.
for side in (1, -1):
    ev, ef = icosphere(1)
    centre = (side * 0.27, 0.2, 0.68)
    base = len(out)
    out += [tuple(c + 0.17 * x for c, x in zip(centre, p)) for p in ev]
    faces += [(a + base, b + base, c + base) for a, b, c in ef]
print("# head: icosphere level %d on a (%g, %g, %g) ellipsoid with features, and two"
      " eyeballs; radii scaled by 1 + %g * (u - 0.5), u uniform (Python random, seed %d)"
      % (level, *shape, amp, seed))
for p in out:
    print("v %.6f %.6f %.6f" % p)
for a, b, c in faces:
    print("f %d %d %d" % (a + 1, b + 1, c + 1))
