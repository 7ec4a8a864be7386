"""The ray tests of :func:`robotool.sim.ray_cast.cast`, compiled: a Warp kernel on the CPU, one thread per ray, each
testing the eligible geoms in index order and keeping the nearest hit (the first of equals).

Each shape's test is MuJoCo's (``engine_ray.c``) with its arithmetic in the same order and without fused
multiply-adds, so every product and sum rounds as in ``mj_ray`` and the answers are the same to the bit. Warp loads
the first time a ray is cast.
"""

from __future__ import annotations

import mujoco
import numpy as np
import warp as wp

from robotool.sim.warp_runtime import Float, Floats, Floats2, Floats3, Int, Ints, Vec3, launch_on_cpu

wp.set_module_options({"fuse_fp": False})  # no fused multiply-adds: each product and sum rounds as mj_ray's do

PLANE, SPHERE, CAPSULE, ELLIPSOID, CYLINDER, BOX = (
    wp.constant(int(t))
    for t in (
        mujoco.mjtGeom.mjGEOM_PLANE,
        mujoco.mjtGeom.mjGEOM_SPHERE,
        mujoco.mjtGeom.mjGEOM_CAPSULE,
        mujoco.mjtGeom.mjGEOM_ELLIPSOID,
        mujoco.mjtGeom.mjGEOM_CYLINDER,
        mujoco.mjtGeom.mjGEOM_BOX,
    )
)
MINVAL = wp.constant(Float(1e-15))  # MuJoCo's mjMINVAL
MISS = wp.constant(Float(-1.0))


@wp.func
def _row(values: Floats3, a: Int, b: Int) -> Vec3:
    """``values[a, b]``, three numbers, as a vector."""
    return Vec3(values[a, b, 0], values[a, b, 1], values[a, b, 2])


@wp.func
def _root(a: Float, b: Float, c: Float, which: Float) -> Float:
    """One root of a x^2 + 2 b x + c = 0: ``which`` -1 the lesser, +1 the greater (-1 when none is real)."""
    det = b * b - a * c
    if det < Float(0.0) or a < MINVAL:
        return MISS
    root = wp.sqrt(det)
    if which < Float(0.0):
        return (-b - root) / a
    return (-b + root) / a


@wp.func
def _least_root(a: Float, b: Float, c: Float) -> Float:
    """The least non-negative root of a x^2 + 2 b x + c = 0 (-1: none)."""
    x0 = _root(a, b, c, Float(-1.0))
    if x0 >= Float(0.0):
        return x0
    x1 = _root(a, b, c, Float(1.0))
    if x1 >= Float(0.0):
        return x1
    return MISS


@wp.func
def _nearer(x: Float, sol: Float, ok: bool) -> Float:
    """``sol`` where ``ok`` and it is nearer than ``x`` (or ``x`` is no hit yet), else ``x``."""
    if ok and (x < Float(0.0) or sol < x):
        return sol
    return x


@wp.func
def _sphere_hit(pos: Vec3, radius_sqr: Float, pnt: Vec3, vec: Vec3) -> Float:
    """MuJoCo's ray_sphere: the least non-negative distance to a sphere of squared radius ``radius_sqr`` (-1)."""
    d0 = pnt[0] - pos[0]
    d1 = pnt[1] - pos[1]
    d2 = pnt[2] - pos[2]
    a = vec[0] * vec[0] + vec[1] * vec[1] + vec[2] * vec[2]
    b = vec[0] * d0 + vec[1] * d1 + vec[2] * d2
    c = d0 * d0 + d1 * d1 + d2 * d2 - radius_sqr
    return _least_root(a, b, c)


@wp.func
def _local(pos: Vec3, mat: Floats, m: int, p: Vec3) -> Vec3:
    """``mat`` (9 values from ``m``)' (``p`` - ``pos``): a point in the geom's frame (``pos`` 0 for a direction)."""
    d0 = p[0] - pos[0]
    d1 = p[1] - pos[1]
    d2 = p[2] - pos[2]
    return Vec3(
        mat[m + 0] * d0 + mat[m + 3] * d1 + mat[m + 6] * d2,
        mat[m + 1] * d0 + mat[m + 4] * d1 + mat[m + 7] * d2,
        mat[m + 2] * d0 + mat[m + 5] * d1 + mat[m + 8] * d2,
    )


@wp.func
def _plane(p: Vec3, v: Vec3, size: Vec3) -> Float:
    if v[2] > -MINVAL:  # hit from its front only
        return MISS
    x = -p[2] / v[2]
    if x < Float(0.0):
        return MISS
    a = p[0] + x * v[0]
    b = p[1] + x * v[1]
    if (size[0] <= Float(0.0) or wp.abs(a) <= size[0]) and (size[1] <= Float(0.0) or wp.abs(b) <= size[1]):
        return x
    return MISS


@wp.func
def _capsule(p: Vec3, v: Vec3, size: Vec3) -> Float:
    r = size[0]
    h = size[1]
    sol = _least_root(v[0] * v[0] + v[1] * v[1], v[0] * p[0] + v[1] * p[1], p[0] * p[0] + p[1] * p[1] - r * r)
    x = _nearer(MISS, sol, sol >= Float(0.0) and wp.abs(p[2] + sol * v[2]) <= h)
    a = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    for s in range(2):  # the top cap's upper half, then the bottom cap's lower half
        side = Float(1.0)
        if s == 1:
            side = Float(-1.0)
        q2 = p[2] - side * h
        b = v[0] * p[0] + v[1] * p[1] + v[2] * q2
        c = p[0] * p[0] + p[1] * p[1] + q2 * q2 - r * r
        for w in range(2):
            which = Float(-1.0)
            if w == 1:
                which = Float(1.0)
            root = _root(a, b, c, which)
            z = p[2] + root * v[2]
            beyond = z <= -h
            if s == 0:
                beyond = z >= h
            x = _nearer(x, root, root >= Float(0.0) and beyond)
    return x


@wp.func
def _ellipsoid(p: Vec3, v: Vec3, size: Vec3) -> Float:
    s0 = Float(1.0) / (size[0] * size[0])
    s1 = Float(1.0) / (size[1] * size[1])
    s2 = Float(1.0) / (size[2] * size[2])
    a = s0 * v[0] * v[0] + s1 * v[1] * v[1] + s2 * v[2] * v[2]
    b = s0 * v[0] * p[0] + s1 * v[1] * p[1] + s2 * v[2] * p[2]
    c = s0 * p[0] * p[0] + s1 * p[1] * p[1] + s2 * p[2] * p[2] - Float(1.0)
    return _least_root(a, b, c)


@wp.func
def _cylinder(p: Vec3, v: Vec3, size: Vec3) -> Float:
    r = size[0]
    h = size[1]
    x = MISS
    if wp.abs(v[2]) > MINVAL:  # the caps
        for s in range(2):
            side = Float(-1.0)
            if s == 1:
                side = Float(1.0)
            sol = (side * h - p[2]) / v[2]
            a = p[0] + sol * v[0]
            b = p[1] + sol * v[1]
            x = _nearer(x, sol, sol >= Float(0.0) and a * a + b * b <= r * r)
    sol = _least_root(v[0] * v[0] + v[1] * v[1], v[0] * p[0] + v[1] * p[1], p[0] * p[0] + p[1] * p[1] - r * r)
    return _nearer(x, sol, sol >= Float(0.0) and wp.abs(p[2] + sol * v[2]) <= h)


@wp.func
def _box(p: Vec3, v: Vec3, size: Vec3) -> Float:
    """The six faces: the nearest met within its rectangle."""
    x = MISS
    for face in range(6):
        axis = face // 2
        side = Float(-1.0)
        if face % 2 == 1:
            side = Float(1.0)
        j = 0
        k = 2
        if axis == 0:
            j = 1
        if axis == 2:
            k = 1
        if wp.abs(v[axis]) > MINVAL:
            sol = (side * size[axis] - p[axis]) / v[axis]
            a = p[j] + sol * v[j]
            b = p[k] + sol * v[k]
            x = _nearer(x, sol, sol >= Float(0.0) and wp.abs(a) <= size[j] and wp.abs(b) <= size[k])
    return x


@wp.func
def _holds(t: Int, p: Vec3, s: Vec3) -> bool:
    """Whether the point ``p`` (in the geom's frame) lies inside a geom of type ``t`` and size ``s``."""
    radial = p[0] * p[0] + p[1] * p[1]
    if t == SPHERE:
        return p[0] * p[0] + p[1] * p[1] + p[2] * p[2] < s[0] * s[0]
    if t == CAPSULE:
        beyond = wp.max(wp.abs(p[2]) - s[1], Float(0.0))
        return radial + beyond * beyond < s[0] * s[0]
    if t == ELLIPSOID:
        a = p[0] / s[0]
        b = p[1] / s[1]
        c = p[2] / s[2]
        return a * a + b * b + c * c < Float(1.0)
    if t == CYLINDER:
        return radial < s[0] * s[0] and wp.abs(p[2]) < s[1]
    if t == BOX:
        return wp.abs(p[0]) < s[0] and wp.abs(p[1]) < s[1] and wp.abs(p[2]) < s[2]
    return False


@wp.kernel
def _inside(
    kind: Ints,
    size: Floats2,
    body: Ints,
    xpos: Floats3,
    xmat: Floats,
    pnt: Floats3,
    exclude: Ints,
    found: Ints,
):
    """One thread per point, world-major (``exclude`` and ``found`` flat over worlds and points)."""
    i = wp.tid()
    w = i // pnt.shape[1]
    point = _row(pnt, w, i % pnt.shape[1])
    ngeom = kind.shape[0]
    which = Int(-1)
    for c in range(ngeom):
        if body[c] != exclude[i]:
            local = _local(_row(xpos, w, c), xmat, (w * ngeom + c) * 9, point)
            if _holds(kind[c], local, Vec3(size[c, 0], size[c, 1], size[c, 2])):
                which = Int(c)
    found[i] = which


@wp.func
def _bounded(t: Int) -> bool:
    """Whether ``mj_ray`` tests a shape's bounding sphere first (a capsule, cylinder or box)."""
    if t == CAPSULE:
        return True
    if t == CYLINDER:
        return True
    return t == BOX


@wp.kernel
def _cast(
    kind: Ints,
    size: Floats2,
    bound: Floats,
    body: Ints,
    xpos: Floats3,
    xmat: Floats,
    pnt: Floats3,
    vec: Floats3,
    exclude: Ints,
    from_inside: Int,
    dist: Floats,
    hit: Ints,
):
    """One thread per ray, world-major (``exclude``, ``dist`` and ``hit`` flat over worlds and rays); with
    ``from_inside`` 1, a ray that starts inside a geom meets it there (distance 0)."""
    i = wp.tid()
    w = i // pnt.shape[1]
    start = _row(pnt, w, i % pnt.shape[1])
    direction = _row(vec, w, i % pnt.shape[1])
    best = MISS
    found = Int(-1)
    holder = Int(-1)  # the last geom the ray starts inside
    ngeom = kind.shape[0]
    for c in range(ngeom):
        if body[c] == exclude[i]:
            continue
        pos = _row(xpos, w, c)
        half = Vec3(size[c, 0], size[c, 1], size[c, 2])
        t = kind[c]
        m = (w * ngeom + c) * 9
        if from_inside != 0 and _holds(t, _local(pos, xmat, m, start), half):
            holder = Int(c)
        x = MISS
        if t == SPHERE:
            x = _sphere_hit(pos, half[0] * half[0], start, direction)
        elif not _bounded(t) or _sphere_hit(pos, bound[c], start, direction) >= Float(0.0):
            p = _local(pos, xmat, m, start)
            v = _local(Vec3(), xmat, m, direction)
            if t == PLANE:
                x = _plane(p, v, half)
            elif t == CAPSULE:
                x = _capsule(p, v, half)
            elif t == ELLIPSOID:
                x = _ellipsoid(p, v, half)
            elif t == CYLINDER:
                x = _cylinder(p, v, half)
            elif t == BOX:
                x = _box(p, v, half)
        if x >= Float(0.0) and (found < 0 or x < best):
            best = x
            found = Int(c)
    if holder >= 0:
        best = Float(0.0)
        found = holder
    dist[i] = best
    hit[i] = found


def cast(
    kind: np.ndarray,
    size: np.ndarray,
    bound: np.ndarray,
    body: np.ndarray,
    xpos: np.ndarray,
    xmat: np.ndarray,
    pnt: np.ndarray,
    vec: np.ndarray,
    exclude: np.ndarray,
    from_inside: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Rays ``pnt + x * vec`` (w, n, 3) against k geoms (their ``kind``, ``size`` (k, 3), squared bounding radius
    ``bound`` and ``body``) posed at ``xpos`` (w, k, 3) and ``xmat`` (w, k, 9), each ray leaving out the body
    ``exclude`` (w, n) (-1: none): the least distance x >= 0 (-1 where nothing is hit) and the hit geom's position
    among the k (-1), (w, n). With ``from_inside``, a ray that starts inside one of the geoms (the last of several,
    as :func:`inside` finds it) meets it at distance 0."""
    _check_shapes(kind, size, body, xpos, xmat, pnt, exclude, bound=bound, vec=vec)
    shape = pnt.shape[:2]
    dist, hit = np.empty(shape), np.empty(shape, dtype=np.int32)
    if dist.size:
        geoms = (_ints(kind), _floats(size), _floats(bound), _ints(body))
        rays = (_floats(pnt), _floats(vec), _ints(exclude), int(from_inside))
        launch_on_cpu(_cast, dist.size, *geoms, *_poses(xpos, xmat), *rays, dist.reshape(-1), hit.reshape(-1))
    return dist, hit.astype(int)


def inside(
    kind: np.ndarray,
    size: np.ndarray,
    body: np.ndarray,
    xpos: np.ndarray,
    xmat: np.ndarray,
    pnt: np.ndarray,
    exclude: np.ndarray,
) -> np.ndarray:
    """The geom among k (their ``kind``, ``size`` (k, 3) and ``body``, posed at ``xpos`` (w, k, 3) and ``xmat``
    (w, k, 9)) that each point ``pnt`` (w, n, 3) lies inside, the body ``exclude`` (w, n) left out: its position among
    the k (the last of several; -1: none), (w, n). A plane holds nothing."""
    _check_shapes(kind, size, body, xpos, xmat, pnt, exclude)
    found = np.empty(pnt.shape[:2], dtype=np.int32)
    if found.size:
        geoms = (_ints(kind), _floats(size), _ints(body))
        launch_on_cpu(_inside, found.size, *geoms, *_poses(xpos, xmat), _floats(pnt), _ints(exclude), found.reshape(-1))
    return found.astype(int)


def _check_shapes(
    kind: np.ndarray,
    size: np.ndarray,
    body: np.ndarray,
    xpos: np.ndarray,
    xmat: np.ndarray,
    pnt: np.ndarray,
    exclude: np.ndarray,
    bound: np.ndarray | None = None,
    vec: np.ndarray | None = None,
) -> None:
    """Refuse arrays whose shapes do not match (the kernels read them by index, unchecked)."""
    k, (w, n) = len(kind), np.shape(pnt)[:2]
    expected = [
        ("size", size, (k, 3)),
        ("body", body, (k,)),
        ("xpos", xpos, (w, k, 3)),
        ("xmat", xmat, (w, k, 9)),
        ("pnt", pnt, (w, n, 3)),
        ("exclude", exclude, (w, n)),
        *([("bound", bound, (k,))] if bound is not None else []),
        *([("vec", vec, (w, n, 3))] if vec is not None else []),
    ]
    for name, values, shape in expected:
        if np.shape(values) != shape:
            raise ValueError(f"{name} has shape {np.shape(values)}, not {shape}")


def _floats(values: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64)


def _ints(values: np.ndarray) -> np.ndarray:
    """Flat int32 values (the kernels index per-ray values by the ray's flat index): ``values`` itself where they are
    so already."""
    flat = np.ascontiguousarray(values, dtype=np.int32)
    return flat if flat.ndim == 1 else flat.reshape(-1)


def _poses(xpos: np.ndarray, xmat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions (w, k, 3) and rotations flat, as the kernels read them."""
    return _floats(xpos), _floats(xmat).reshape(-1)
