"""The scene's graph questions (rigid parts, coupling to the drive) asked of networkx.

References: the hand-written union-find (scene/files.py) and fixed-point
reachability (scene/model.py) they replaced, kept here verbatim in substance,
on random body/pin and node/edge sets; the parts must come out identical,
order included (node names and error messages depend on it).
"""

import random
from types import SimpleNamespace

import pytest

from mechcirc.errors import GeometryError
from mechcirc.scene.files import _rigid_parts
from mechcirc.scene.model import _check_connected


def _old_parts(lk, bodies, tbodies):
    parent = {b: b for b in bodies}

    def find(b):
        while parent[b] != b:
            parent[b] = parent[parent[b]]
            b = parent[b]
        return b

    for p in lk.pose:
        if p in lk.ground:
            continue
        on = [b for b, pts in bodies.items() if p in pts and b not in tbodies]
        for b in on[1:]:
            parent[find(b)] = find(on[0])
    groups = {}
    for b in bodies:
        groups.setdefault(find(b), []).append(b)
    return [tuple(g) for g in groups.values()]


def _old_reach(node_of_part, edges):
    reach = {node_of_part[0]}
    changed = True
    while changed:
        changed = False
        for a, b in edges:
            if (a in reach) != (b in reach) and "0" not in (a, b):
                reach |= {a, b}
                changed = True
    return [n for n in node_of_part if n not in reach]


@pytest.mark.parametrize("seed", range(300))
def test_rigid_parts_equal_the_union_find(seed):
    rng = random.Random(seed)
    points = [f"P{i}" for i in range(rng.randint(1, 12))]
    ground = set(rng.sample(points, rng.randint(0, min(3, len(points)))))
    names = [f"b{i}" for i in range(rng.randint(1, 9))]
    rng.shuffle(names)                       # body order is not alphabetical
    bodies = {b: tuple(rng.sample(points, rng.randint(1, min(3, len(points)))))
              for b in names}
    tbodies = set(rng.sample(names, rng.randint(0, 2) if len(names) > 2 else 0))
    lk = SimpleNamespace(pose={p: (0.0, 0.0) for p in points}, ground=ground, sliders=())
    assert _rigid_parts(lk, bodies, tbodies) == _old_parts(lk, bodies, tbodies)


@pytest.mark.parametrize("seed", range(300))
def test_coupling_to_the_drive_equals_the_fixed_point(seed):
    rng = random.Random(seed)
    nodes = [f"n{i}" for i in range(rng.randint(1, 10))]
    pool = nodes + ["0", "p_port"]
    edges = [tuple(rng.sample(pool, 2)) if rng.random() < 0.9 else (rng.choice(pool),) * 2
             for _ in range(rng.randint(0, 12))]
    lost = _old_reach(nodes, edges)
    scene = SimpleNamespace(source="s.toml")
    dropped = [("k9", "does not deform in the rigid motion")]
    if not lost:
        _check_connected(scene, nodes, edges, dropped, 12.0)
        return
    with pytest.raises(GeometryError) as info:
        _check_connected(scene, nodes, edges, dropped, 12.0)
    assert str(info.value) == (
        f"s.toml: at θ = 12° the parts {', '.join(lost)} are not coupled to the drive: the "
        "elastic elements that would couple them do not deform in the rigid motion (k9: does "
        "not deform in the rigid motion); a dead centre")
