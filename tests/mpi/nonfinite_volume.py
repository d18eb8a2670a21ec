"""A float volume whose NaN and +Inf voxels lie in different bricks of a 2-rank split (along x):
the NaN slab in the brick without the whole volume's finite minimum, the +Inf slab in the one
without its maximum, and a third NaN slab across the plane the bricks share. One process replaces
them with the whole volume's extremes; so must bricks."""
import array, math

DIMS = (48, 40, 36)
TF = [[-0.05, 0.2, 0.4, 1, 0.02], [0.3, 0.2, 0.4, 1, 0.02], [1.05, 1, 0.8, 0.3, 0.3]]
CAMERA = {"eye": [23.5, -90, 60], "center": [23.5, 19.5, 17.5], "up": [0, 0, 1], "fov_y": 35}
NAN_X, INF_X = (30, 33), (10, 13)  # the slabs' x ranges (inclusive)
# A third slab, NaN, across the plane the two bricks share (x = 23 or 24) and inside both
# bricks' ghosts: each voxel of it must be counted once, and replaced alike on both sides.
SHARED_X = (20, 27)


def write(path):
    nx, ny, nz = DIMS
    vals = array.array("f")
    for z in range(nz):
        for y in range(ny):
            for x in range(nx):
                v = x / (nx - 1) + 0.05 * math.sin(0.3 * y + 0.2 * z)
                if NAN_X[0] <= x <= NAN_X[1] and 10 <= y <= 30:
                    v = float("nan")
                elif INF_X[0] <= x <= INF_X[1] and 10 <= y <= 30:
                    v = float("inf")
                elif SHARED_X[0] <= x <= SHARED_X[1] and y <= 3:
                    v = float("nan")
                vals.append(v)
    path.write_bytes(f"NRRD0004\ntype: float\ndimension: 3\nsizes: {nx} {ny} {nz}\nencoding: raw\n"
                     "endian: little\n\n".encode() + vals.tobytes())
    return path
