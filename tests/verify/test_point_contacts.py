"""Contacts of every type (main paper Remark 3.11): interlock/verify/point_contacts.py and their rows."""

import math

import numpy as np
import pytest
import trimesh

from interlock.blocks import Assembly, presets
from interlock.blocks.contact import Contact
from interlock.verify import check, interlocking_matrix
from interlock.verify.admissible import cone_pressure, unless_cones
from interlock.verify.contacts import ContactError, contacts
from interlock.verify.point_contacts import contact_kinds
from interlock.verify.tangent_cones import admissible_normals

# --- the rows Remark 3.11 predicts, against hand-written matrices -------------------------------------------


def _turned_cube(axis, centre):
    """A unit cube turned by 45 degrees about ``axis`` (0: x, 1: y), centred at ``centre``."""
    cube = trimesh.creation.box()
    angle = math.pi / 4
    cube.apply_transform(trimesh.transformations.rotation_matrix(angle, np.eye(3)[axis]))
    cube.apply_translation(centre)
    return cube


def _hand_rows(points, normals, blocks, free, centroids, length):
    """Rows of Def. 3.3 written out: for p, n from block i to block j, -(r_i x n, n) on i and (r_j x n, n) on j."""
    rows = []
    for p, n, (i, j) in zip(points, normals, blocks):
        row = np.zeros(6 * len(free))
        for b, sign in ((i, -1.0), (j, 1.0)):
            if b in free:
                k = free.index(b)
                r = (np.asarray(p) - centroids[b]) / length
                row[6 * k:6 * k + 6] = sign * np.r_[np.cross(r, n), n]
        rows.append(row)
    return np.array(rows)


def _same_rows(computed, hand):
    order = lambda m: m[np.lexsort(np.round(m, 9).T[::-1])]  # noqa: E731 (rows compared as sets)
    assert computed.shape == hand.shape
    np.testing.assert_allclose(order(computed), order(hand), atol=1e-12)


def test_crossed_cubes_edge_to_edge_give_the_cross_product_row():
    # block 0's top edge runs along x at z = sqrt 2 / 2; block 1's bottom edge along y, crossing it at (0.3, 0, h)
    h = math.sqrt(0.5)
    lower, upper = _turned_cube(0, [0, 0, 0]), _turned_cube(1, [0.3, 0, 2 * h])
    pair = Assembly.from_meshes([lower, upper])
    found = contacts(pair, kinds="all")
    assert [(c.i, c.j, c.kind) for c in found] == [(0, 1, "edge-edge")]
    (c,) = found
    np.testing.assert_allclose(c.vertices[0], [0.3, 0, h], atol=1e-12)
    np.testing.assert_allclose(c.normal, [0, 0, 1], atol=1e-12)  # e_0 x e_1 = x x y, from block 0 to block 1
    assert contacts(pair) == ()  # the face-only model sees nothing
    A = interlocking_matrix(pair, frame=[], contacts=found)
    hand = _hand_rows([[0.3, 0, h]], [np.array([0.0, 0, 1])], [(0, 1)], [0, 1], pair.centroids, A.length_scale)
    _same_rows(A.matrix.toarray(), hand)
    assert hand[0, 1] != 0  # the lower cube's moment about y is in the row: (p - c_0) x n = (0, -0.3, 0)


def test_tetrahedron_apex_in_a_face_gives_the_face_normal_row():
    floor = trimesh.creation.box(bounds=[[-2, -2, -1], [2, 2, 0]])
    ceiling = trimesh.creation.box(bounds=[[-2, -2, 1], [2, 2, 2]])
    base = np.array([[1, 0, 0], [-0.5, math.sqrt(3) / 2, 0], [-0.5, -math.sqrt(3) / 2, 0]])
    apex = np.array([0.2, 0.1, 1.0])
    tetrahedron = trimesh.Trimesh(np.vstack([base, apex]), [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]])
    assert tetrahedron.is_volume
    a = Assembly.from_meshes([floor, ceiling, tetrahedron], frame=[0, 1])
    found = contacts(a, kinds="all")
    assert [(c.i, c.j, c.kind) for c in found] == [(0, 2, "face"), (1, 2, "vertex-face")]
    point = found[1]
    np.testing.assert_allclose(point.vertices[0], apex, atol=1e-12)
    np.testing.assert_allclose(point.normal, [0, 0, -1], atol=1e-12)  # the ceiling's face normal, towards block 2
    assert point.facet_i >= 0 and point.facet_j == -1  # the face is block 1's, the vertex block 2's
    A = interlocking_matrix(a, contacts=found)
    up, down = np.array([0.0, 0, 1]), np.array([0.0, 0, -1])
    hand = _hand_rows(list(base) + [apex], [up] * 3 + [down], [(0, 2)] * 3 + [(1, 2)], [2], a.centroids,
                      A.length_scale)
    _same_rows(A.matrix.toarray(), hand)
    # the apex row blocks lifting: without it the tetrahedron lifts off the floor
    assert check(a, contacts="faces").interlocked is False
    assert check(a).motion_kind != "opening" or check(a).interlocked is not False


# --- a block held by edge-edge contacts only ---------------------------------------------------------------

_T = np.array([(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)], dtype=float)
# (axis, side, s): a small tetrahedron beyond face side * e_axis of the cube [-1, 1]^3 whose edge crosses the big
# tetrahedron's edge in that face at parameter s; seven of them hold it (rows chosen to span R^6 positively)
_HOLDERS = [(0, 1, -0.45), (0, -1, 0.03), (1, 1, 0.39), (1, -1, -0.46), (2, 1, 0.35), (2, -1, 0.31), (0, 1, 0.44)]


def _outward(vertices, faces):
    """Faces of a tetrahedron turned so that each faces away from the opposite vertex."""
    out = []
    for face in faces:
        a, b, c = vertices[list(face)]
        other = vertices[[k for k in range(4) if k not in face][0]]
        out.append(face if np.cross(b - a, c - a) @ (a - other) > 0 else face[::-1])
    return trimesh.Trimesh(vertices, out, process=False)


def _tetrahedron(scale=1.0, shift=(0, 0, 0)):
    return _outward(_T * scale + np.asarray(shift, dtype=float), [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)])


def _holder(axis, side, s, size=0.3, offset=0.1):
    centre = [1 + size, s - offset, s + offset] if side > 0 else [-1 - size, s - offset, -s - offset]
    turn = np.roll(np.eye(3), axis, axis=0)  # x -> e_axis, a symmetry of the tetrahedron
    return _outward((_T * size + centre) @ turn.T, [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)])


def _held(holders):
    meshes = [_tetrahedron()] + [_holder(*h) for h in holders]
    return Assembly.from_meshes(meshes, frame=list(range(1, len(meshes))))


def test_tetrahedron_held_by_edge_edge_contacts_only_is_interlocked():
    a = _held(_HOLDERS)
    found = contacts(a, kinds="all")
    assert contact_kinds(found) == {"edge-edge": 7}
    assert contacts(a) == ()  # no face touches a face
    v = check(a)
    assert v.interlocked is True and v.contact_kinds == {"edge-edge": 7}
    assert "7 edge-edge" in str(v) and v.to_dict()["contact_kinds"] == {"edge-edge": 7}
    assert check(a, contacts="faces").interlocked is False  # today's face-only model: nothing holds it


@pytest.mark.parametrize("removed", range(len(_HOLDERS)))
def test_one_edge_contact_removed_the_tetrahedron_moves_out(removed):
    a = _held(_HOLDERS[:removed] + _HOLDERS[removed + 1:])
    first = check(a)
    assert first.interlocked is False and first.moving == (0,)
    v = check(a, order=2)
    assert v.interlocked is False and v.finite_motion.shown  # followed without overlap: a real motion


# --- Fig. 5 and the face-only model ------------------------------------------------------------------------


@pytest.mark.parametrize("symmetry", ["p4", "p3"])
def test_fig5_tetrahedra_with_the_outer_ring_fixed_are_interlocked(symmetry):
    layer = presets.tetrahedra(symmetry)
    v = check(layer)
    assert v.interlocked is True and v.contact_kinds["edge-edge"] > 0
    ring = check(layer, frame=layer.boundary())  # p4: Fig. 5a's ring without the red class inside
    assert ring.interlocked is True
    # faces alone leave a sliding motion (the limit issue 38 reported: p4 ring kernel 5, p3 kernel 13)
    assert check(layer, frame=layer.boundary(), contacts="faces").interlocked is False


def test_fig5c_p6_layer_with_the_outer_ring_fixed_comes_apart():
    # the paper gives no coordinates; with this preset's slopes the six blocks about the 6-fold centre slide out
    v = check(presets.tetrahedra("p6"), order=2)
    assert v.interlocked is False and v.finite_motion.shown
    assert v.moving == (0, 1, 2, 3, 4, 5)


def test_faces_only_model_and_degenerate_touches_leave_face_verdicts_unchanged():
    grid = presets.cube_grid()
    v, faces = check(grid), check(grid, contacts="faces")
    assert str(v) == str(faces) and v.contacts == faces.contacts == 12
    # the diagonal neighbours' shared corners: a cone of normals each, no row
    assert v.contact_kinds == {"face": 12, "vertex-vertex (cone)": 16} and faces.contact_kinds == {"face": 12}
    assert v.shape == faces.shape
    cubes = presets.interlocking_cubes()
    assert str(check(cubes)) == str(check(cubes, contacts="faces"))


def test_contact_model_names_are_checked():
    with pytest.raises(ContactError, match="kinds"):
        contacts(presets.cube_grid(), kinds="edges")
    with pytest.raises(Exception, match="'all' or 'faces'"):
        check(presets.cube_grid(), contacts="edges")


# --- cones of normals -------------------------------------------------------------------------------------


def test_corner_to_corner_cubes_have_a_cone_and_a_motion_that_does_not_press_into_it():
    a = Assembly.from_meshes([trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]),
                              trimesh.creation.box(bounds=[[1, 1, 1], [2, 2, 2]])], frame=[0])
    (c,) = contacts(a, kinds="all")
    assert c.kind == "vertex-vertex" and c.normals is not None and len(c.normals) == 3
    np.testing.assert_allclose(c.vertices[0], [1, 1, 1])
    v = check(a)
    assert v.interlocked is False and v.shape[0] == 0
    assert cone_pressure(v.motion, [c], a.centroids)[0] <= 1e-9


def test_a_motion_pressing_into_a_cone_along_every_normal_is_no_answer():
    a = Assembly.from_meshes([trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]]),
                              trimesh.creation.box(bounds=[[1, 1, 1], [2, 2, 2]])], frame=[0])
    found = contacts(a, kinds="all")
    v = check(a)
    into = np.zeros((2, 6))
    into[1, 3:] = [-1, -1, -1]  # block 1 straight into block 0's corner
    import dataclasses

    pressing = dataclasses.replace(v, motion=into, motion_kind="opening")
    assert cone_pressure(into, found, a.centroids)[0] > 0
    judged = unless_cones(pressing, found, a.centroids)
    assert judged.interlocked is None and "vertex-vertex" in judged.status
    reversible = unless_cones(dataclasses.replace(pressing, motion_kind="sliding"), found, a.centroids)
    assert reversible.interlocked is False and reversible.motion[1, 3] == 1  # the reverse presses into nothing


def test_admissible_normals_of_a_face_an_edge_and_a_corner():
    x, y, z = np.eye(3)
    face = [x, -x, y, -y, -z]  # the half-space below z = 0
    corner_above = [x, y, z]  # a cube's corner standing on it
    np.testing.assert_allclose(admissible_normals(face, corner_above), [[0, 0, 1]])
    assert len(admissible_normals(face, [x + z, -x + z, y - z])) == 0  # a corner reaching through the face
    crossing = admissible_normals([x, -x, -z + y, -z - y], [y, -y, z + x, z - x])  # edges along x and y
    np.testing.assert_allclose(crossing, [[0, 0, 1]], atol=1e-12)


def test_point_contacts_survive_a_file():
    found = contacts(_held(_HOLDERS), kinds="all") + contacts(presets.cube_grid(), kinds="all")[-1:]
    for c in found:
        back = Contact.from_dict(c.to_dict())
        assert back.kind == c.kind and back.to_dict() == c.to_dict()
        assert (back.normals is None) == (c.normals is None)
    assert "edge-edge contact 0-" in str(found[0])


def test_local_slides_decide_layers_where_the_whole_kernel_collides():
    # the honeycomb layer (radius 2, ring fixed) is not infinitesimally interlocked even with every contact type;
    # its kernel vector moves many blocks into each other, but a local one (three blocks) slides out
    layer = presets.honeycomb_layer(2.0)
    v = check(layer, order=2)
    assert v.interlocked is False and v.finite_motion.shown and len(v.finite_motion.moving) <= 6


def _touches(found):
    """Point contacts as comparable tuples, and face contacts by their pair, normal and area."""
    points = sorted((c.i, c.j, c.kind, tuple(np.round(c.vertices[0], 9) + 0.0), tuple(np.round(c.normal, 9) + 0.0),
                     None if c.normals is None else len(c.normals)) for c in found if c.kind != "face")
    faces = sorted((c.i, c.j, tuple(np.round(c.normal, 9) + 0.0), round(c.area, 9)) for c in found if c.kind == "face")
    return points, faces


@pytest.mark.parametrize("mirror", [False, True])
def test_instanced_blocks_give_the_point_contacts_of_their_world_meshes(mirror):
    layer = presets.tetrahedra("p6", radius=1.5)
    if mirror:  # the whole layer reflected: every block placed by a transform of determinant -1
        layer = Assembly(layer.meshes, layer.types, np.diag([-1.0, 1, 1, 1]) @ layer.transforms, frame=layer.frame)
        assert layer.mirrored.all()
    instanced = contacts(layer, kinds="all")
    assert len(layer.pair_kinds(np.array(sorted(layer.neighbours.edges)))[0]) < len(instanced)  # the shared path
    one_by_one = contacts(Assembly.from_meshes(layer.world_meshes(), frame=layer.frame), kinds="all")
    assert _touches(instanced) == _touches(one_by_one)


def test_a_slide_blocked_only_by_crossed_edges_is_followed_or_blocked():
    from interlock.verify.motion import finite_motion

    h = math.sqrt(0.5)
    pair = Assembly.from_meshes([_turned_cube(0, [0, 0, 0]), _turned_cube(1, [0.3, 0, 2 * h])], frame=[0])
    down, up, along = np.zeros((2, 6)), np.zeros((2, 6)), np.zeros((2, 6))
    down[1, 5], up[1, 5], along[1, 3] = -1.0, 1.0, 1.0
    assert not finite_motion(pair, down).shown  # into the crossed edge: the edges press into each other
    assert finite_motion(pair, up).shown and finite_motion(pair, along).shown  # away, and along the row's kernel
    v = check(pair, order=2)
    assert v.interlocked is False and v.finite_motion.shown
    assert cone_pressure(v.motion, contacts(pair, kinds="all"), pair.centroids)[0] <= 1e-9


def _cone_contact(i, j, point, normals, kind="vertex-vertex"):
    import dataclasses

    normals = np.array(normals, dtype=float)
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    normals.setflags(write=False)
    c = Contact.at_points(i, j, normals.sum(axis=0), [point])
    return dataclasses.replace(c, kind=kind, normals=normals, tolerance=0.0)


def test_cone_search_proves_no_motion_when_every_branch_is_empty():
    from interlock.verify.admissible import cone_search

    # block 1 may only slide along x (faces above, below, in front, behind); one cone forbids +x, one -x
    a = Assembly.from_meshes([trimesh.creation.box(bounds=[[-5, -5, -5], [-4, -4, -4]]),
                              trimesh.creation.box(bounds=[[0, 0, 0], [1, 1, 1]])], frame=[0])
    rows = [Contact.at_points(0, 1, [0, 0, 1], [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]),
            Contact.at_points(0, 1, [0, 0, -1], [[0, 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]]),
            Contact.at_points(0, 1, [0, 1, 0], [[0, 0, 0], [1, 0, 0], [0, 0, 1], [1, 0, 1]]),
            Contact.at_points(0, 1, [0, -1, 0], [[0, 1, 0], [1, 1, 0], [0, 1, 1], [1, 1, 1]])]
    A = interlocking_matrix(a, contacts=rows, translational=True)
    cones = [_cone_contact(0, 1, [1, 0.5, 0.5], [[-1, 0.1, 0], [-1, -0.1, 0]]),  # some normal sees -x: no +x
             _cone_contact(0, 1, [0, 0.5, 0.5], [[1, 0, 0.1], [1, 0, -0.1]])]  # and no -x
    assert cone_search(A, cones, a.centroids)[1] == "none"
    motion, kind, _ = cone_search(A, cones[:1], a.centroids)  # one cone only: the block slides along -x
    assert kind in ("opening", "sliding") and motion[0][1, 3] < 0 and motion[1] == (1,)
