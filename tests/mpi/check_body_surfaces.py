"""Checks the bodies' surfaces of a run directory's field snapshots (docs/outputs.md), with python3's
standard library and h5dump (hdf5-tools) only, so it runs without the tools' venv.

    python3 check_body_surfaces.py RUN_DIR MODE [ARGS]

MODE
  xdmf BODIES       fields.xdmf parses (xml.dom.minidom); every time of the temporal collection has
                    the Triangle grids body_1 .. body_BODIES, and every HDF DataItem of the file
                    names a dataset that exists with the Dimensions the XDMF states (h5dump -H).
  geometry          every vertex of every body of every snapshot lies on the spheroid of the pose
                    stored next to it: x = R(q)^T (v - c), |(x/a)^2 + (y/b)^2 + (z/b)^2 - 1| <= 1e-12;
                    the centre lies in the box [0, L); faces are 0-based vertex indices, oriented
                    outward (normal . (face centroid - centre) > 0).
  steps S1,S2,...   the temporal collection lists exactly these steps.
  same OTHER_DIR    every snapshot's surfaces (vertices, faces, pose) equal OTHER_DIR's bit for bit
                    (both directories list the same steps).
Exit status 0 when the check holds; the reason is printed otherwise.
"""
import os
import re
import subprocess
import sys
import xml.dom.minidom as minidom

TOLERANCE = 1.0e-12


def children(element, tag):
    return [c for c in element.childNodes if c.nodeType == 1 and c.tagName == tag]


def time_grids(run):
    document = minidom.parse(os.path.join(run, "fields.xdmf"))
    temporal = children(children(document.documentElement, "Domain")[0], "Grid")[0]
    assert temporal.getAttribute("CollectionType") == "Temporal"
    return document, children(temporal, "Grid")


def h5_values(path, dataset):
    """The values of a dataset in file order (h5dump with 17 significant digits)."""
    out = subprocess.run(["h5dump", "-y", "-w", "0", "-m", "%.17g", "-d", dataset, path],
                         capture_output=True, text=True)
    assert out.returncode == 0, (path, dataset, out.stderr)
    data = out.stdout[out.stdout.index("DATA {") + 6:]
    data = data[:data.index("}")]
    return [float(x) for x in re.findall(r"[-+0-9.eE]+", data)]


def h5_dims(path, dataset):
    out = subprocess.run(["h5dump", "-H", "-d", dataset, path], capture_output=True, text=True)
    assert out.returncode == 0, (path, dataset, out.stderr)
    match = re.search(r"SIMPLE \{ \( ([0-9, ]+) \)", out.stdout)
    return match.group(1).replace(",", " ").split() if match else []


def snapshot_files(run):
    return sorted(f for f in os.listdir(run) if re.fullmatch(r"fields_[0-9]{10}\.h5", f))


def surface_names(path):
    out = subprocess.run(["h5dump", "-d", "/surface_names", path], capture_output=True, text=True)
    assert out.returncode == 0, (path, out.stderr)
    return re.search(r'DATA \{\s*\(0\): "([^"]*)"', out.stdout).group(1).split()


def rotation(q):
    w, x, y, z = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def check_xdmf(run, bodies):
    document, grids = time_grids(run)
    assert grids, "no times in fields.xdmf"
    want = [f"body_{n}" for n in range(1, bodies + 1)]
    for grid in grids:
        names = [g.getAttribute("Name") for g in children(grid, "Grid")
                 if children(g, "Topology")[0].getAttribute("TopologyType") == "Triangle"]
        assert names == want, (grid.getAttribute("Name"), names)
    count = 0
    for item in document.getElementsByTagName("DataItem"):
        if item.getAttribute("Format") != "HDF":
            continue
        name, dataset = item.firstChild.data.strip().split(":")
        dims = h5_dims(os.path.join(run, name), dataset)
        assert dims == item.getAttribute("Dimensions").split(), (name, dataset, dims)
        count += 1
    print(f"{len(grids)} times, {count} datasets with the stated shapes")


def check_geometry(run):
    worst, checked = 0.0, 0
    for name in snapshot_files(run):
        path = os.path.join(run, name)
        box = h5_values(path, "/grid/lengths")
        for body in surface_names(path):
            group = f"/surfaces/{body}"
            c = h5_values(path, group + "/centre")
            q = h5_values(path, group + "/orientation")
            a, b = h5_values(path, group + "/semi_axes")
            v = h5_values(path, group + "/vertices")
            f = [int(x) for x in h5_values(path, group + "/faces")]
            assert all(0.0 <= c[i] < box[i] for i in range(3)), ("centre outside the box", name, body, c)
            r = rotation(q)
            vertices = [v[i:i + 3] for i in range(0, len(v), 3)]
            for p in vertices:
                d = [p[i] - c[i] for i in range(3)]
                x = [sum(r[i][k] * d[i] for i in range(3)) for k in range(3)]   # R^T d
                worst = max(worst, abs((x[0] / a) ** 2 + (x[1] / b) ** 2 + (x[2] / b) ** 2 - 1.0))
                checked += 1
            assert min(f) == 0 and max(f) == len(vertices) - 1, ("face indices", name, body, min(f), max(f))
            for t in range(0, len(f), 3):
                p1, p2, p3 = (vertices[f[t + k]] for k in range(3))
                e1 = [p2[i] - p1[i] for i in range(3)]
                e2 = [p3[i] - p1[i] for i in range(3)]
                n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
                g = [(p1[i] + p2[i] + p3[i]) / 3 - c[i] for i in range(3)]
                assert sum(n[i] * g[i] for i in range(3)) > 0.0, ("inward face", name, body, t // 3)
    print(f"{checked} vertices, largest |quadric - 1| = {worst:.3e}")
    assert checked > 0, "no surfaces"
    assert worst <= TOLERANCE, f"a vertex off its spheroid: {worst:.3e} > {TOLERANCE:g}"


def check_steps(run, steps):
    _, grids = time_grids(run)
    listed = [int(g.getAttribute("Name").split("_")[1]) for g in grids]
    print("steps", listed)
    assert listed == steps, (listed, steps)


def check_same(run, other):
    files = snapshot_files(run)
    assert files == snapshot_files(other), (files, snapshot_files(other))
    for name in files:
        bodies = surface_names(os.path.join(run, name))
        assert bodies == surface_names(os.path.join(other, name)), name
        for body in bodies:
            for item in ("vertices", "faces", "centre", "orientation", "semi_axes"):
                dataset = f"/surfaces/{body}/{item}"
                assert (h5_values(os.path.join(run, name), dataset)
                        == h5_values(os.path.join(other, name), dataset)), (name, dataset)
    print(f"{len(files)} snapshots with the same surfaces")


def main():
    run, mode = sys.argv[1], sys.argv[2]
    try:
        if mode == "xdmf":
            check_xdmf(run, int(sys.argv[3]))
        elif mode == "geometry":
            check_geometry(run)
        elif mode == "steps":
            check_steps(run, [int(s) for s in sys.argv[3].split(",")])
        elif mode == "same":
            check_same(run, sys.argv[3])
        else:
            raise SystemExit(f"unknown mode {mode}")
    except AssertionError as error:
        print("check failed:", error)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
