"""The Python module `viewcells` (python/): a scene from numpy arrays or a file, baked with the
command line's options and defaults, read back as arrays. Run by ctest (tests/CMakeLists.txt)
with the system Python 3 and PYTHONPATH at the built module; VIEWCELLS_CLI names the executable."""
import importlib.util
import json
import os
import subprocess

import numpy as np
import pytest

import viewcells

CLI = os.environ["VIEWCELLS_CLI"]


def run(*args, cwd):
    return subprocess.run([CLI, "-q", *args], cwd=cwd, check=True, capture_output=True, text=True).stdout


def read_obj(path):
    """The OBJ the generator writes, as arrays: vertices, triangles, each triangle's group, names."""
    vertices, triangles, groups, names = [], [], [], []
    for line in open(path):
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            vertices.append([float(x) for x in t[1:4]])
        elif t[0] in ("o", "g"):
            names.append(t[1])
        elif t[0] == "f":
            idx = [int(x.split("/")[0]) - 1 for x in t[1:]]
            for k in range(1, len(idx) - 1):  # a fan, as the OBJ reader triangulates
                triangles.append([idx[0], idx[k], idx[k + 1]])
                groups.append(len(names) - 1)
    return np.array(vertices), np.array(triangles), np.array(groups), names


@pytest.fixture(scope="module")
def office(tmp_path_factory):
    d = tmp_path_factory.mktemp("office")
    run("generate", "office", "--size", "1", "-o", "office.obj", cwd=d)
    return d


SETTINGS = dict(cells=12, samples=20000, max_cells=60, agvs_samples=50000)


def test_arrays_file_and_command_line_bake_the_same_file(office):
    run("bake", "office.obj", "--cells", "12", "--samples", "20000", "--max-cells", "60", "--agvs-samples", "50000",
        "-o", "cli.pvs", cwd=office)
    from_file = viewcells.bake(str(office / "office.obj"), str(office / "file.pvs"), **SETTINGS)
    v, t, g, names = read_obj(office / "office.obj")
    scene = viewcells.Scene(v, t, objects=g, names=names, name="office.obj")
    assert scene.fingerprint == viewcells.Scene.load(str(office / "office.obj")).fingerprint
    from_arrays = viewcells.bake(scene, str(office / "arrays.pvs"), **SETTINGS)
    cli = (office / "cli.pvs").read_bytes()
    assert (office / "file.pvs").read_bytes() == cli
    assert (office / "arrays.pvs").read_bytes() == cli
    assert from_arrays.cell_count == from_file.cell_count == 12
    assert from_arrays.report["cells"] == 12 and from_arrays.report["budget"]["cells"] == 12


def test_results_agree_with_query(office):
    baked = viewcells.bake(str(office / "office.obj"), str(office / "q.pvs"), **SETTINGS)
    bounds = baked.cell_bounds
    assert bounds.shape == (baked.cell_count, 2, 3)
    assert np.all(bounds[:, 0, :] < bounds[:, 1, :])
    rng = np.random.default_rng(3)
    lo, hi = bounds[:, 0, :].min(axis=0), bounds[:, 1, :].max(axis=0)
    for p in rng.uniform(lo, hi, size=(20, 3)):
        cell = baked.query(tuple(p))
        q = json.loads(run("query", "q.pvs", *map(repr, p), "--json", cwd=office))
        assert cell == q["cell"]
        assert list(baked.pvs(cell)) == [o["id"] for o in q["pvs"]]
        assert np.all(bounds[cell, 0] <= p) and np.all(p <= bounds[cell, 1])
    assert baked.query((1e9, 0, 0)) == -1
    assert len(baked.object_names) == baked.object_count == 24


def test_progress_and_see_through_and_errors(office, tmp_path):
    lines = []
    # Two boxes and a glass pane between them: the pane is seen, but hides nothing.
    box = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    faces = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5],
                      [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
    pane = np.array([[2, -1, -1], [2, 2, -1], [2, 2, 2], [2, -1, 2]], float)
    v = np.vstack([box, box + [4, 0, 0], pane])
    t = np.vstack([faces, faces + 8, [[16, 17, 18], [16, 18, 19]]])
    objects = np.array([0] * 12 + [1] * 12 + [2] * 2)
    scene = viewcells.Scene(v, t, objects=objects, names=["left", "right", "glass"], see_through=[False, False, True])
    baked = viewcells.bake(scene, str(tmp_path / "glass.pvs"), cells=2, samples=20000, agvs_samples=20000,
                           view_box="-1,-2,-1,6,3,2", progress=lines.append)
    assert any("bake:" in line for line in lines), lines[:5]
    seen = set()
    for c in range(baked.cell_count):
        seen.update(baked.pvs(c).tolist())
    assert seen == {0, 1, 2}, "both boxes seen through the glass"
    with pytest.raises(viewcells.Error, match=r"raise max_cells \(keyword\) or lower cells \(keyword\)"):
        viewcells.bake(scene, str(tmp_path / "x.pvs"), cells=5, max_cells=2)
    with pytest.raises(viewcells.Error, match=r"needs a budget: cells \(keyword\) N or memory \(keyword\)"):
        viewcells.bake(scene, str(tmp_path / "x.pvs"))
    with pytest.raises(viewcells.Error, match="NaN or infinite"):
        viewcells.Scene(np.array([[np.nan, 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]))
    with pytest.raises(viewcells.Error, match=r"triangle 0 \(counting from 0\) has vertex index 99, not from 0 to 7"):
        viewcells.Scene(box, np.array([[0, 1, 99]]))
    with pytest.raises(viewcells.Error, match=r"unknown option no_such_option \(keyword\)"):
        viewcells.bake(scene, str(tmp_path / "x.pvs"), cells=2, no_such_option=3)
    assert not (tmp_path / "x.pvs").exists()


def polyhedron_volume(vertices, faces):
    """Volume of a closed polyhedron whose faces are counter-clockwise seen from outside."""
    total = 0.0
    for f in faces:
        a = vertices[f[0]]
        for k in range(1, len(f) - 1):
            total += np.dot(a, np.cross(vertices[f[k]], vertices[f[k + 1]])) / 6
    return total


def test_cells_as_convex_pieces_fill_the_view_box(office):
    baked = viewcells.bake(str(office / "office.obj"), str(office / "p.pvs"), **SETTINGS)
    bounds = baked.cell_bounds
    box_lo, box_hi = bounds[:, 0].min(axis=0), bounds[:, 1].max(axis=0)
    total = 0.0
    for c in range(baked.cell_count):
        pieces = baked.polyhedra(c)
        assert pieces, f"cell {c} has no piece"
        for vertices, faces in pieces:
            volume = polyhedron_volume(vertices, faces)
            assert volume > 0, "faces counter-clockwise from outside give a positive volume"
            total += volume
            assert np.all(vertices >= bounds[c, 0] - 1e-9) and np.all(vertices <= bounds[c, 1] + 1e-9)
            assert baked.query(tuple(vertices.mean(axis=0))) == c  # a convex piece holds its centroid
    assert total == pytest.approx(np.prod(box_hi - box_lo), rel=1e-9)
    with pytest.raises(viewcells.Error, match="no view cell"):
        baked.polyhedra(baked.cell_count)


def test_merge_history_cuts_are_the_bakes_of_fewer_cells(office):
    baked = viewcells.bake(str(office / "office.obj"), str(office / "h.pvs"), **SETTINGS)
    n = baked.cell_count
    group, lists = baked.cut(n)
    assert list(group) == list(range(n)) and all(list(lists[c]) == list(baked.pvs(c)) for c in range(n))
    group, lists = baked.cut(1)
    assert set(group) == {0} and set(lists[0]) == set().union(*(set(baked.pvs(c)) for c in range(n)))
    with pytest.raises(viewcells.Error, match="cuts from 1 to 12"):
        baked.cut(n + 1)
    with pytest.raises(viewcells.Error, match="cuts from 1 to 12"):
        baked.cut(0)
    # The cut of 5 is the partition a bake of 5 cells from the same hierarchy makes: every point
    # lies in the same group of either (a bijection of group ids), and a group's PVS is the
    # union of its cells'.
    group, lists = baked.cut(5)
    assert sorted(set(group)) == list(range(5))
    for g in range(5):
        assert set(lists[g]) == set().union(*(set(baked.pvs(c)) for c in range(n) if group[c] == g))
    five = viewcells.bake(str(office / "office.obj"), str(office / "h5.pvs"), **dict(SETTINGS, cells=5))
    rng = np.random.default_rng(5)
    lo, hi = baked.cell_bounds[:, 0].min(axis=0), baked.cell_bounds[:, 1].max(axis=0)
    pairs = {(int(group[baked.query(tuple(p))]), five.query(tuple(p))) for p in rng.uniform(lo, hi, size=(2000, 3))}
    assert len(pairs) == len({a for a, _ in pairs}) == len({b for _, b in pairs}) == 5, sorted(pairs)


def test_cell_meshes_costs_and_gltf_need_the_right_scene(office, tmp_path):
    scene = viewcells.Scene.load(str(office / "office.obj"))
    baked = viewcells.bake(scene, str(tmp_path / "m.pvs"), **SETTINGS)
    meshes, costs = baked.cell_meshes, baked.cell_costs
    assert len(meshes) == len(costs) == baked.cell_count
    triangles = np.array(scene.object_triangles)
    for c, (vertices, tris) in enumerate(meshes):
        assert vertices.shape[1] == 3 and tris.shape[1] == 3 and tris.max() < len(vertices)
        assert np.all(vertices >= baked.cell_bounds[c, 0] - 1e-4) and np.all(vertices <= baked.cell_bounds[c, 1] + 1e-4)
        # r(PVS) with the default cost model, a = 100 per object and b = 1 per triangle
        assert costs[c] == pytest.approx(np.maximum(100, triangles[baked.pvs(c)]).sum())
    baked.write_gltf(str(tmp_path / "m.glb"))
    assert (tmp_path / "m.glb").read_bytes()[:4] == b"glTF"
    again = viewcells.read(str(tmp_path / "m.pvs"), str(office / "office.obj"))
    assert np.array_equal(again.cell_costs, costs) and again.report == {}
    with pytest.raises(viewcells.Error, match="needs the scene"):
        viewcells.read(str(tmp_path / "m.pvs")).cell_costs
    other = viewcells.Scene(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float), np.array([[0, 1, 2]]))
    with pytest.raises(viewcells.Error, match="fingerprints differ"):
        viewcells.read(str(tmp_path / "m.pvs"), other)


def write_png(path, rgb):
    """An RGB image (h, w, 3) of uint8 as a PNG, with zlib alone."""
    import struct
    import zlib

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + row.tobytes() for row in rgb)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def cost_colour(t):
    """blue -> cyan -> green -> yellow -> red for t in [0, 1] (the viewers' scale), per element."""
    stops = np.array([(0, 0, 1), (0, 1, 1), (0, 1, 0), (1, 1, 0), (1, 0, 0)], float)
    x = np.clip(t, 0, 1) * 4
    i = np.minimum(x.astype(int), 3)
    f = (x - i)[..., None]
    return stops[i] + (stops[i + 1] - stops[i]) * f


def test_a_slice_through_the_cells_from_python(office):
    """docs/python.md's picture: the office's cells at eye height, drawn from query() and
    cell_costs alone (blue cheapest to red costliest, borders between cells and the walls' cut
    dark), written to $VIEWCELLS_TEST_OUT/python-slice.png."""
    scene = viewcells.Scene.load(str(office / "office.obj"))
    baked = viewcells.bake(scene, str(office / "s.pvs"), **SETTINGS)
    lo, hi = baked.cell_bounds[:, 0].min(axis=0), baked.cell_bounds[:, 1].max(axis=0)
    z = lo[2] + 1.6
    width = 480
    height = int(round(width * (hi[1] - lo[1]) / (hi[0] - lo[0])))
    xs = lo[0] + (np.arange(width) + 0.5) * (hi[0] - lo[0]) / width
    ys = hi[1] - (np.arange(height) + 0.5) * (hi[1] - lo[1]) / height
    cell = np.array([[baked.query((x, y, z)) for x in xs] for y in ys])
    assert np.all(cell >= 0), "every point of the view box has a cell"
    costs = baked.cell_costs
    t = (costs[cell] - costs.min()) / max(costs.max() - costs.min(), 1e-300)
    rgb = cost_colour(t) * 0.85 + 0.15
    border = np.zeros(cell.shape, bool)
    border[:, 1:] |= cell[:, 1:] != cell[:, :-1]
    border[1:, :] |= cell[1:, :] != cell[:-1, :]
    rgb[border] = 0.25
    # The walls' cut: every triangle that crosses the plane z, drawn as its segment.
    v = scene.vertices[scene.triangles]  # (M, 3, 3)
    for tri in v:
        d = tri[:, 2] - z
        if d.min() > 0 or d.max() < 0:
            continue
        points = [tri[a] + (tri[b] - tri[a]) * (d[a] / (d[a] - d[b])) for a, b in ((0, 1), (1, 2), (2, 0))
                  if (d[a] < 0) != (d[b] < 0)]
        if len(points) != 2:
            continue
        for s in np.linspace(0, 1, 400):
            p = points[0] + (points[1] - points[0]) * s
            i = int((hi[1] - p[1]) / (hi[1] - lo[1]) * height)
            j = int((p[0] - lo[0]) / (hi[0] - lo[0]) * width)
            if 0 <= i < height and 0 <= j < width:
                rgb[i, j] = 0.0
    shown = set(np.unique(cell))
    assert len(shown) >= baked.cell_count // 2, f"a slice at eye height crosses most cells: {sorted(shown)}"
    out = os.environ.get("VIEWCELLS_TEST_OUT")
    if out:
        os.makedirs(out, exist_ok=True)
        write_png(os.path.join(out, "python-slice.png"), (rgb * 255).astype(np.uint8))


def test_the_measured_stop_from_python(office, tmp_path):
    """holes= is --holes: the bake measures frames and stops once few enough show a hole; the
    report, as a dict, says what the frames saw and what the run measured on the way."""
    baked = viewcells.bake(str(office / "office.obj"), str(tmp_path / "holes.pvs"),
                           **dict(SETTINGS, agvs_samples=None), holes="10%", measure_size="256x192", time=120)
    m = baked.report["measured_pixel_error"]
    assert (m["width"], m["height"], m["cameras"]) == (256, 192, 1000)
    assert m["cameras_with_wrong_pixels"] <= 0.10 * m["cameras"]
    curve = baked.report["measured_curve"]
    assert curve and curve[-1]["frames_with_wrong_pixels_share"] <= 0.10


def test_with_pvs_rewrites_the_lists_through_the_same_hierarchy(office, tmp_path):
    baked = viewcells.bake(str(office / "office.obj"), str(tmp_path / "a.pvs"), **SETTINGS)
    lists = [baked.pvs(c).tolist() for c in range(baked.cell_count)]
    same = baked.with_pvs(str(tmp_path / "same.pvs"), lists)
    assert (tmp_path / "same.pvs").read_bytes() == (tmp_path / "a.pvs").read_bytes()
    extra = next(o for o in range(baked.object_count) if o not in lists[0])
    lists[0] = lists[0] + [extra]
    edited = baked.with_pvs(str(tmp_path / "edited.pvs"), lists)
    assert extra in edited.pvs(0).tolist()
    assert all(edited.pvs(c).tolist() == baked.pvs(c).tolist() for c in range(1, baked.cell_count))
    assert len(same.neighbours) == baked.cell_count and all(c not in n for c, n in enumerate(same.neighbours))
    with pytest.raises(viewcells.Error, match="not one of the file's 24 objects"):
        baked.with_pvs(str(tmp_path / "bad.pvs"), [[10**6]] * baked.cell_count)
    assert not (tmp_path / "bad.pvs").exists()


def boxes_scene(ids, names=None):
    """Closed unit cubes along x, cube k with object id ids[k]."""
    box = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    faces = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4], [1, 2, 6], [1, 6, 5],
                      [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
    v = np.vstack([box + [3 * k, 0, 0] for k in range(len(ids))])
    t = np.vstack([faces + 8 * k for k in range(len(ids))])
    return v, t, np.repeat(np.array(ids), 12)


QUICK = dict(cells=2, samples=5000, agvs_samples=5000, view_box="-1,-2,-1,12,3,2")


def test_the_callers_object_ids_are_kept(tmp_path):
    """Issue 67: objects=[0, 5, 9] stays 0, 5, 9 in every PVS (it was renumbered 0, 1, 2), and an
    object whose triangles are all degenerate keeps its id and is never listed."""
    v, t, o = boxes_scene([0, 5, 9])
    scene = viewcells.Scene(v, t, objects=o)
    assert scene.object_count == 10
    baked = viewcells.bake(scene, str(tmp_path / "ids.pvs"), **QUICK)
    seen = set()
    for c in range(baked.cell_count):
        seen.update(baked.pvs(c).tolist())
    assert seen == {0, 5, 9}
    # Object 1: one degenerate triangle (all three corners the same point), then object 2.
    v, t, o = boxes_scene([0, 2])
    t = np.vstack([t, [[0, 0, 0]]])
    o = np.append(o, 1)
    scene = viewcells.Scene(v, t, objects=o, names=["a", "flat", "b"])
    assert scene.names == ["a", "flat", "b"] and scene.object_triangles == [12, 0, 12]
    baked = viewcells.bake(scene, str(tmp_path / "flat.pvs"), **QUICK)
    seen = set()
    for c in range(baked.cell_count):
        seen.update(baked.pvs(c).tolist())
    assert seen == {0, 2}


def test_arguments_are_checked_before_any_work(tmp_path):
    """Issue 67: wrong types, fractional indices, flags given to valued options, help and a
    missing directory are errors that name what is wrong, raised before the bake starts."""
    v, t, o = boxes_scene([0, 1])
    scene = viewcells.Scene(v, t, objects=o)
    # The crash this was (SIGSEGV), in a subprocess: a regression fails the test, not the run.
    crash = subprocess.run([os.sys.executable, "-c", "import viewcells\ntry:\n viewcells.bake(None, 'x.pvs', cells=5)\n"
                            "except TypeError as e:\n print('TypeError:', e)"], capture_output=True, text=True,
                           cwd=tmp_path, env=os.environ, timeout=60)
    assert crash.returncode == 0 and "scene must be a viewcells.Scene or a scene file's path, not NoneType" in crash.stdout, \
        (crash.returncode, crash.stdout, crash.stderr)
    with pytest.raises(TypeError, match="output must be a path"):
        viewcells.bake(scene, 3, cells=5)
    with pytest.raises(viewcells.Error, match=r"whole numbers: entry 2 is 2\.9"):
        viewcells.Scene(v, np.vstack([[0, 1, 2.9], t]).astype(float))
    assert viewcells.Scene(v, t.astype(float), objects=o).fingerprint == scene.fingerprint
    with pytest.raises(viewcells.Error, match="whole numbers"):
        viewcells.Scene(v, t, objects=o + 0.5)
    with pytest.raises(viewcells.Error, match=r"objects: entry 0 is 2147483647; object ids must be from 0 to 2\^24 - 1"):
        viewcells.Scene(v, t, objects=np.full(len(t), 2**31 - 1))
    with pytest.raises(viewcells.Error, match=r"cells \(keyword\): 'true' is not allowed: give a whole number from 1"):
        viewcells.bake(scene, str(tmp_path / "x.pvs"), cells=True)
    with pytest.raises(viewcells.Error, match="help is not an option of a bake from code") as e:
        viewcells.bake(scene, str(tmp_path / "x.pvs"), cells=2, help=True)
    assert "agvs_samples=" in str(e.value) and "caught in your main" not in str(e.value)
    # The keywords and their help come from the library's table, as the command line's do.
    assert "max_cells=INT in [1, 10000000]" in viewcells.bake.__doc__
    assert "near_samples=" in viewcells.bake.__doc__ and "conservative=True|False" in viewcells.bake.__doc__
    with pytest.raises(viewcells.Error, match=r"seed \(keyword\): '-1' is not allowed"):
        viewcells.bake(scene, str(tmp_path / "x.pvs"), cells=2, seed=-1)
    with pytest.raises(viewcells.Error, match=r"seed \(keyword\): '100000000000000000000' is not allowed"):
        viewcells.bake(scene, str(tmp_path / "x.pvs"), cells=2, seed=10**20)
    with pytest.raises(viewcells.Error, match="its directory .* does not exist"):
        viewcells.bake(scene, str(tmp_path / "no" / "x.pvs"), cells=2, samples=10**9)
    assert not (tmp_path / "x.pvs").exists()


def test_outputs_never_replace_inputs(office, tmp_path):
    """Issue 67: a bake or a glTF written over the scene, or a .pvs inside the work directory,
    is refused, and the file is left as it was; report= writes the report."""
    level = tmp_path / "level.obj"
    level.write_bytes((office / "office.obj").read_bytes())
    before = level.read_bytes()
    with pytest.raises(viewcells.Error, match="is the scene being baked"):
        viewcells.bake(str(level), str(level), **SETTINGS)
    assert level.read_bytes() == before
    baked = viewcells.bake(level, tmp_path / "l.pvs", **SETTINGS, report=tmp_path / "l.json")
    assert json.loads((tmp_path / "l.json").read_text())["cells"] == 12
    with pytest.raises(viewcells.Error, match="is the scene this .pvs was baked from"):
        viewcells.read(str(tmp_path / "l.pvs"), str(level)).write_gltf(str(level))
    with pytest.raises(viewcells.Error, match="is the scene this .pvs was baked from"):
        baked.write_gltf(level)
    assert level.read_bytes() == before
    with pytest.raises(viewcells.Error, match="is the .pvs or the scene of this bake: write the report elsewhere"):
        viewcells.bake(str(level), str(tmp_path / "r.pvs"), **SETTINGS, report=str(level))
    work = tmp_path / "wd"
    work.mkdir()
    with pytest.raises(viewcells.Error, match="inside the work directory"):
        viewcells.bake(str(level), str(work / "hierarchy.vcells"), **SETTINGS, work=str(work))
    assert list(work.iterdir()) == []


def test_threads_keep_their_own_outputs(office, tmp_path):
    """Issue 67: a glTF written while another thread bakes is there when write_gltf returns
    (it waited for that bake's end), and two bakes at once in one process both succeed."""
    import threading
    first = viewcells.bake(str(office / "office.obj"), str(tmp_path / "first.pvs"), **SETTINGS)
    results, errors = {}, []

    def bake(name, **extra):
        try:
            results[name] = viewcells.bake(str(office / "office.obj"), str(tmp_path / name), **dict(SETTINGS, **extra))
        except Exception as e:  # noqa: BLE001 - reported below
            errors.append(e)

    threads = [threading.Thread(target=bake, args=("a.pvs",)), threading.Thread(target=bake, args=("b.pvs",))]
    for th in threads:
        th.start()
    first.write_gltf(str(tmp_path / "during.glb"))
    assert (tmp_path / "during.glb").read_bytes()[:4] == b"glTF"
    for th in threads:
        th.join()
    assert not errors, errors
    assert (tmp_path / "a.pvs").read_bytes() == (tmp_path / "b.pvs").read_bytes() == (tmp_path / "first.pvs").read_bytes()


INTERRUPTED = r"""
import os, signal, sys, threading, time
import viewcells
out = sys.argv[2]
threading.Timer(1.0, lambda: os.kill(os.getpid(), signal.SIGINT)).start()
start = time.time()
try:
    viewcells.bake(sys.argv[1], out, cells=12, samples=20000, max_cells=60, agvs_time=120, pixel_error=1e-9)
except KeyboardInterrupt:
    print("interrupted after %.2f s; written: %s" % (time.time() - start, os.path.exists(out)))
"""


def test_ctrl_c_stops_a_bake_and_writes_nothing(office, tmp_path):
    """Issue 67: Ctrl-C during bake() raises KeyboardInterrupt (it was ignored until the bake
    ended, which then wrote its file). The bake asked for runs 120 s: without the stop the
    test would see no KeyboardInterrupt at all."""
    script = tmp_path / "interrupted.py"
    script.write_text(INTERRUPTED)
    out = subprocess.run([os.sys.executable, str(script), str(office / "office.obj"), str(tmp_path / "i.pvs")],
                         capture_output=True, text=True, timeout=240, env=os.environ)
    assert "interrupted after" in out.stdout and "written: False" in out.stdout, out.stdout + out.stderr
    assert not (tmp_path / "i.pvs").exists()


def test_play_space_keywords(office, tmp_path):
    """The play space's options are keywords: a start point and a body change what bake finds,
    and the report says which view space was chosen and why."""
    def view_space(**kw):
        report = tmp_path / "play.json"
        viewcells.bake(str(office / "office.obj"), str(tmp_path / "play.pvs"), cells=4, samples=5000,
                       agvs_samples=5000, report=str(report), **kw)
        return json.load(open(report))["settings"]["view_space"]
    default = view_space()
    assert default.startswith("the play space") and "no start points" in default, default
    started = view_space(start="2,2,0.5", eye_band="1,2")
    assert "reachable from 1 of 1 start points" in started and "1.00-2.00 m" in started, started
    assert "the whole view box" in view_space(no_play_space=True)
    with pytest.raises(viewcells.Error, match="eye_band \\(keyword\\) takes LO,HI"):
        view_space(eye_band="2,1")


def test_play_space_from_python(office, tmp_path):
    """viewcells.play_space finds what bake uses: the office's floors (its slab top, z = 0.3),
    drawable; a start point far outside reaches nothing, and a Quake 3 map has none from floors."""
    play = viewcells.play_space(str(office / "office.obj"))
    assert play.found, play.rule
    v, t = play.floors
    assert v.shape[1] == 3 and t.shape[1] == 3 and len(t) > 0 and t.max() < len(v)
    assert np.all(v[:, 2] >= 0.3 + 0.03 - 1e-3), v[:, 2].min()  # never below the ground floor
    assert np.count_nonzero(np.abs(v[:, 2] - 0.33) < 1e-3) > len(v) // 2  # mostly the floor itself
    # The floors' rectangles are the reached floor area with an eye band (the roof, at the scene's
    # top, has none).
    tri = v[t].astype(np.float64)
    drawn = 0.5 * np.abs(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])[:, 2]).sum()
    assert abs(drawn - play.floor_area_m2) < 1e-4 * play.floor_area_m2, (drawn, play.floor_area_m2)
    points = play.points(200, seed=3)
    assert points.shape == (200, 3) and all(play.contains(p) for p in points)
    lo, hi = np.array(play.box)
    assert np.all(points >= lo - 1e-9) and np.all(points <= hi + 1e-9)
    assert play.volume_m3 > 0 and play.metres_per_unit == 1
    nowhere = viewcells.play_space(str(office / "office.obj"), start=[(1e4, 0, 0)], only_from_starts=True)
    assert not nowhere.found and "reachable from 0 of 1 start points" in nowhere.rule
    with pytest.raises(viewcells.Error, match="no play space"):
        nowhere.floors
    with pytest.raises(viewcells.Error, match="eye band"):
        viewcells.play_space(str(office / "office.obj"), eye_band=(2, 1))
    with pytest.raises(TypeError, match="play_space: scene must be"):
        viewcells.play_space(3)


def test_the_table_of_options_is_the_command_lines(tmp_path):
    """bake_options() is the library's table that `viewcells bake --help` and bake()'s keywords
    are made from; the Blender add-on reads its extra option words with it."""
    table = viewcells.bake_options()
    by_flag = {o["flag"]: o for o in table}
    assert by_flag["--max-cells"]["keyword"] == "max_cells" and by_flag["--max-cells"]["kind"] == "whole"
    assert by_flag["--prove-hidden"]["negation"] == "--no-prove-hidden"
    assert by_flag["--start"]["kind"] == "texts" and by_flag["--samples"]["default"] == "1000000"
    cli = os.environ.get("VIEWCELLS_CLI")
    if cli:
        helped = subprocess.run([cli, "bake", "--help"], capture_output=True, text=True, check=True).stdout
        for o in table:
            assert o["flag"] in helped and o["help"][:40] in helped.replace("\n", " "), o["flag"]
    spec = importlib.util.spec_from_file_location(
        "addon_options", os.path.join(os.path.dirname(__file__), "..", "..", "tools", "blender", "viewcells_blender",
                                      "options.py"))
    addon = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(addon)
    words = addon.option_words("--no-ga --start 1,2,0 --start=5,2,0 --no-prove-hidden --holes=1% --samples 30000 "
                               "--conservative=false", table)
    assert words == {"no_ga": True, "start": ["1,2,0", "5,2,0"], "prove_hidden": False, "holes": "1%",
                     "samples": "30000", "conservative": False}, words
    with pytest.raises(ValueError, match="'--nope' is not an option"):
        addon.option_words("--nope 3", table)
    with pytest.raises(ValueError, match="--samples needs a value"):
        addon.option_words("--samples", table)
