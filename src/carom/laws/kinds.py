"""Body kinds: how a body answers an impulse, as the body table and the kernels store it
(codes kept with the laws, so that a kernel reading them is rebuilt when they change)."""

KIND_DYNAMIC = 0  # moved by gravity and impulses
KIND_STATIC = 1  # never moves
KIND_KINEMATIC = 2  # moves at its own velocity and spin, unmoved by impulses

#: every body kind by name, in one table (``World.add_body(kind=...)``, a scene's ``kind``,
#: checkpoints and H5MD store the codes)
BODY_KINDS = {"dynamic": KIND_DYNAMIC, "static": KIND_STATIC, "kinematic": KIND_KINEMATIC}
#: each code's name
KIND_NAMES = {code: name for name, code in BODY_KINDS.items()}
