"""Graph questions of mechcirc.topology, checked against hand-drawn small networks."""

import pytest

from mechcirc import parse
from mechcirc.errors import TopologyError
from mechcirc.topology import (check_frame_paths, force_groups, loaded_groups, node_names,
                               reachable)

TREE = """\
drive V 1 0 velocity=1
mass m1 1 0 2
spring k1 1 2 100
mass m2 2 0 1
spring k2 3 4 5
lever L 2 0 5 0 ratio=2
"""


def test_force_groups_one_pair_per_element_six_per_lever():
    c = parse(TREE)
    g = force_groups(c.elements, c.levers)
    assert g[:4] == [[("1", "0")], [("1", "2")], [("2", "0")], [("3", "4")]]
    assert sorted(map(sorted, g[4])) == sorted(map(sorted, [
        ("2", "0"), ("2", "5"), ("2", "0"), ("0", "5"), ("0", "0"), ("5", "0")]))
    assert len(g[4]) == 6


def test_node_names_in_order_of_first_appearance():
    c = parse(TREE)
    assert node_names(c.elements, c.levers) == ["1", "0", "2", "3", "4", "5"]


def test_loaded_groups_drops_the_island_and_keeps_the_loop():
    c = parse(TREE)
    kept = loaded_groups(force_groups(c.elements, c.levers), "1", "0")
    # k2 (3–4) is an island; m1, k1, m2 close loops with the drive; the lever's
    # primary 2–0 lies in the drive's block, so its clique is kept with it.
    assert 3 not in kept
    assert {0, 1, 2} <= set(kept)


def test_loaded_groups_unconnected_drive_raises():
    with pytest.raises(TopologyError, match="not connected"):
        loaded_groups([[("1", "2")]], "1", "3")


def test_reachable_respects_blocked_node():
    adj = {"a": {"b"}, "b": {"a", "c"}, "c": {"b", "d"}, "d": {"c"}}
    assert reachable(adj, "a") == {"a", "b", "c", "d"}
    assert reachable(adj, "a", blocked="c") == {"a", "b"}
    assert reachable(adj, "z") == {"z"}


def test_check_frame_paths_flags_a_node_reached_only_through_a_lever():
    bad = parse("drive V 1 0 velocity=1\nmass m 1 0 1\nlever L 1 0 5 6 ratio=2\n"
                "spring k 5 6 3\n")
    with pytest.raises(TopologyError, match="no path to the frame") as info:
        check_frame_paths(bad)
    assert set(info.value.nodes) == {"5", "6"}
    assert "L" in info.value.elements


def test_check_frame_paths_accepts_grounded_secondary_and_plain_islands():
    check_frame_paths(parse("drive V 1 0 velocity=1\nmass m 1 0 1\n"
                            "lever L 1 0 5 0 ratio=2\nspring k 5 0 3\n"))
    # an island without levers is unloaded, not singular
    check_frame_paths(parse("drive V 1 0 velocity=1\nmass m 1 0 1\nspring k 7 8 3\n"))


def test_reachable_start_equal_to_blocked_is_not_blocked():
    adj = {"a": {"b"}, "b": {"a"}}
    assert reachable(adj, "a", blocked="a") == {"a", "b"}
