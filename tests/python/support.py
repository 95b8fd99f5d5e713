"""Helpers shared by the Python tests: numpy when the run allows it, and
arrays read back as lists whichever kind they are."""

try:
    import numpy as np
except ImportError:  # run_tests.py --block-numpy, or no numpy installed
    np = None


def as_list(values):
    """numpy arrays and lists alike as (nested) lists."""
    return values.tolist() if hasattr(values, "tolist") else values


def flat(values):
    """A grid's values as one flat list, x fastest."""
    values = as_list(values)
    if values and isinstance(values[0], list):
        return [v for row in values for v in row]
    return list(values)


def netcdf4():
    """The netCDF4 module, or None where it cannot be imported (it needs numpy)."""
    try:
        import netCDF4
    except ImportError:
        return None
    return netCDF4


# A small mesh of mixed polygons on a 4 x 3 lattice of nodes (node i + 4 j at
# (i, 0.5 j)): two quads in the first column, then each lattice square split
# into two triangles. 12 nodes, 10 faces, 21 edges (12 - 21 + 10 = 1).
MESH_NODES = [(float(i), 0.5 * j) for j in range(3) for i in range(4)]
MESH_FACES = [[0, 1, 5, 4], [4, 5, 9, 8]] + [
    tri for i in (1, 2) for j in (0, 1)
    for a in [i + 4 * j] for tri in ([a, a + 1, a + 5], [a, a + 5, a + 4])]


def write_ugrid(path, start_index=1, fill=-999, fields=None):
    """Writes MESH_NODES and MESH_FACES as a UGRID 1.0 file: a mesh_topology
    variable, face_node_connectivity from ``start_index`` with ``fill`` after
    a triangle's three nodes; ``fields`` maps names to one value per face."""
    netCDF4 = netcdf4()
    with netCDF4.Dataset(path, "w") as ds:
        ds.Conventions = "CF-1.8 UGRID-1.0"
        ds.createDimension("node", len(MESH_NODES))
        ds.createDimension("face", len(MESH_FACES))
        ds.createDimension("max_face_nodes", 4)
        mesh = ds.createVariable("mesh", "i4")
        mesh.cf_role = "mesh_topology"
        mesh.topology_dimension = 2
        mesh.node_coordinates = "node_x node_y"
        mesh.face_node_connectivity = "face_nodes"
        mesh.face_dimension = "face"
        x = ds.createVariable("node_x", "f8", ("node",))
        y = ds.createVariable("node_y", "f8", ("node",))
        x.units = y.units = "m"  # projected: without units, numbers within +-90 look like degrees
        x[:] = [p[0] for p in MESH_NODES]
        y[:] = [p[1] for p in MESH_NODES]
        faces = ds.createVariable("face_nodes", "i4", ("face", "max_face_nodes"), fill_value=fill)
        faces.cf_role = "face_node_connectivity"
        faces.start_index = start_index
        faces[:] = [[n + start_index for n in f] + [fill] * (4 - len(f)) for f in MESH_FACES]
        for name, values in (fields or {}).items():
            ds.createVariable(name, "f8", ("face",))[:] = values
