"""D-space slices (paper Fig. 3) and D-obstacles / D_free membership (paper §3.2)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely

from deformclosure import Part, mesh_part
from deformclosure.dspace import (DiscFinger, HalfPlaneFinger, PointFinger, PolygonFinger, corotational_energy,
                                  dfree_slice, dobstacle_mask, in_dfree, in_dt, linear_energy)
from deformclosure.errors import DeformClosureError

MAT = {"youngs_modulus": 2e6, "poisson_ratio": 0.3, "thickness": 0.002, "elastic_limit_strain": 0.5}


@pytest.fixture(scope="module")
def lmesh():
    """An L-shaped part (m), ~200 nodes."""
    part = Part.from_dict({"name": "L", "units": "m",
                           "outer": [[0, 0], [0.04, 0], [0.04, 0.02], [0.02, 0.02], [0.02, 0.04], [0, 0.04]],
                           "material": MAT, "mesh": {"max_area": 6e-6}})
    return mesh_part(part)


@pytest.fixture(scope="module")
def fingers():
    """Fingers close to the reflex corner (0.02, 0.02) and elsewhere, not touching at rest."""
    return [DiscFinger((0.0245, 0.0245), 0.003), PointFinger((0.021, 0.0225)),
            PolygonFinger(((0.022, 0.0202), (0.026, 0.0202), (0.024, 0.023))),
            HalfPlaneFinger((0.0, -0.0005), (0.0, 1.0))]


def _check_pixels(mesh, res, fingers, energy_kind="linear"):
    iy, ix = np.meshgrid(np.arange(len(res.ys)), np.arange(len(res.xs)), indexing="ij")
    iy, ix = iy.ravel(), ix.ravel()
    Q = np.stack([res.configuration(a, b) for a, b in zip(ix, iy)])
    assert np.array_equal(in_dfree(mesh, Q, fingers), res.free[iy, ix])
    assert np.array_equal(in_dt(mesh, Q), res.in_dt[iy, ix])
    assert np.array_equal(dobstacle_mask(mesh, Q, fingers).T, res.obstacles[:, iy, ix])
    direct = linear_energy(mesh, Q) if energy_kind == "linear" else corotational_energy(mesh, Q)
    assert np.allclose(direct, res.energy[iy, ix], rtol=1e-9, atol=1e-15 * max(direct.max(), 1e-300))


def test_every_pixel_equals_a_direct_call_perimeter_node(lmesh, fingers):
    v = lmesh.find_node((0.02, 0.02))  # the reflex corner: both boundary edges move
    res = dfree_slice(lmesh, None, v, fingers, extent=(0.016, 0.027, 0.016, 0.027), resolution=(41, 37))
    assert res.free.shape == (37, 41)
    # the slice shows all kinds of pixels
    assert res.free.any() and (~res.in_dt).any() and (res.in_dt & ~res.free).any()
    assert all(res.obstacles[i].any() for i in range(3))
    _check_pixels(lmesh, res, fingers)


def test_every_pixel_equals_a_direct_call_deformed_base(lmesh, fingers):
    """Base configuration deformed and the moving node on the outer edge; corotational energy."""
    rng = np.random.default_rng(7)
    q = lmesh.nodes + rng.normal(scale=2e-4, size=lmesh.nodes.shape)
    v = int(lmesh.outer_loop[3])
    x, y = q[v]
    res = dfree_slice(lmesh, q, v, fingers, extent=(x - 0.004, x + 0.004, y - 0.004, y + 0.004), resolution=30,
                      energy="corotational")
    assert res.energy_kind == "corotational"
    _check_pixels(lmesh, res, fingers, energy_kind="corotational")


def test_interior_node_slice(lmesh, fingers):
    interior = np.setdiff1d(np.arange(lmesh.n_nodes), lmesh.perimeter_nodes)
    v = int(interior[len(interior) // 2])
    res = dfree_slice(lmesh, None, v, fingers, resolution=25)
    _check_pixels(lmesh, res, fingers)
    # the base position is free and has zero energy; the rest of the image is no lower
    i = np.argmin(res.energy)
    assert res.energy.ravel()[i] >= 0


def test_dobstacles_match_shapely(lmesh):
    """Independent check of DA membership: overlap area of the deformed part polygon and
    the finger (shapely), on configurations far from touching."""
    rng = np.random.default_rng(8)
    checked = 0
    for _ in range(60):
        q = lmesh.nodes + rng.normal(scale=1e-4, size=lmesh.nodes.shape)
        if not in_dt(lmesh, q):
            continue
        c = rng.uniform(-0.005, 0.045, 2)
        r = rng.uniform(0.001, 0.006)
        verts = c + rng.uniform(0.002, 0.008) * np.array([[0, 0], [1, 0.2], [0.4, 1.0]])
        fs = [DiscFinger(tuple(c), r), PolygonFinger(tuple(map(tuple, verts))), PointFinger(tuple(c)),
              HalfPlaneFinger(tuple(c), (np.cos(r * 1000), np.sin(r * 1000)))]
        part = shapely.Polygon(q[lmesh.outer_loop])
        shapes = [shapely.Point(c).buffer(r, quad_segs=256), shapely.Polygon(verts)]
        got = dobstacle_mask(lmesh, q, fs)
        for k in range(3):
            if k == 2:
                d = part.boundary.distance(shapely.Point(c))
                if d < 1e-6:
                    continue
                assert got[k] == part.contains(shapely.Point(c))
                continue
            s = shapes[k]
            inter = part.intersection(s).area
            if 1e-12 < inter < 1e-9 or part.distance(s) < 1e-7 and inter == 0:
                continue  # too close to touching to compare with a polygonised disc
            assert got[k] == (inter > 0), (k, inter)
        n = np.array([np.cos(r * 1000), np.sin(r * 1000)])
        depth = -np.min((q[lmesh.outer_loop] - c) @ n)
        if abs(depth) > 1e-7:
            assert got[3] == (depth > 0)
        checked += 1
    assert checked > 30


def test_touching_is_free(lmesh):
    """Fingers exactly touching the rest part (edge, reflex corner, flat jaw) are free."""
    fs = [PointFinger((0.02, 0.02)), DiscFinger((0.01, -0.003), 0.003), HalfPlaneFinger((0.04, 0.0), (-1.0, 0.0)),
          PolygonFinger(((0.03, 0.02), (0.035, 0.025), (0.025, 0.025)))]
    assert in_dfree(lmesh, lmesh.nodes, fs)
    moved = lmesh.nodes + [1e-6, 0.0]  # into the jaw on the right
    assert not in_dfree(lmesh, moved, fs)


def test_save_and_errors(lmesh, fingers, tmp_path):
    v = lmesh.find_node((0.02, 0.02))
    res = dfree_slice(lmesh, None, v, fingers, resolution=8)
    res.save(tmp_path / "s.npz")
    z = np.load(tmp_path / "s.npz")
    assert np.array_equal(z["free"], res.free) and z["energy"].shape == (8, 8)
    res.save(tmp_path / "s.json")
    d = json.loads((tmp_path / "s.json").read_text())
    assert d["units"]["energy"] == "J" and len(d["free"]) == 8
    with pytest.raises(DeformClosureError, match="node"):
        dfree_slice(lmesh, None, 10**6, fingers)
    with pytest.raises(DeformClosureError, match="extent"):
        dfree_slice(lmesh, None, v, fingers, extent=(1, 0, 0, 1))
    with pytest.raises(DeformClosureError, match="resolution"):
        dfree_slice(lmesh, None, v, fingers, resolution=1)


def _cli(argv):
    from deformclosure.cli.main import main

    return main(argv)


def test_cli_slice(tmp_path, capsys, examples_dir):
    f = tmp_path / "f.json"
    f.write_text(json.dumps({"units": "mm", "fingers": [{"type": "disc", "center": [-2, 10], "radius": 2}]}))
    out, png = tmp_path / "s.npz", tmp_path / "s.png"
    rc = _cli(["slice", str(examples_dir / "rectangle.json"), "--at", "0,10", "--fingers", str(f),
               "--resolution", "30", "-o", str(out), "--plot", str(png), "--extent", "-2,2,8,12"])
    assert rc == 0
    z = np.load(out)
    assert z["free"].shape == (30, 30) and z["free"].any() and not z["free"].all()
    assert png.stat().st_size > 1000
    assert "D_free" in capsys.readouterr().out
    assert _cli(["slice", str(examples_dir / "rectangle.json"), "--node", "99999", "--fingers", str(f)]) == 2
    assert capsys.readouterr().err.startswith("error: --node")
    assert _cli(["slice", str(examples_dir / "rectangle.json"), "--fingers", str(f)]) == 2
    assert "exactly one of" in capsys.readouterr().err
