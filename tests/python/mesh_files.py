"""Small mesh files in the formats production codes write, for the tests of
dpsm.meshfile, dpsm.config and the BMI component (issue 36). The same
meshes as tests/config/mesh_files.c writes for the C tests.

- write_net_1d2d: Delft3D FM's 1D2D net file (netCDF4): topologies mesh1d,
  network1d (1D) and mesh2d (2D; with ``second_2d`` also mesh2d_refined):
  12 nodes (10 i, 10 j), i < 4, j < 3, units m; 8 faces from 1 (4 squares,
  then 4 right triangles), mesh2d_face_z = 20 + face (location face),
  mesh2d_node_z = 5 + node (location node), boundary tags 1 inflow (x = 0),
  2 outflow (x = 30), 0 the rest.
- write_net_nodes_edges: nodes and int64 edges only (from 0, fill -1), a
  dangling edge to a 13th node; faces built: 4 squares, 4 triangles.
- write_selafin: TELEMAC Selafin, 16 nodes on a 4 x 4 lattice of 10 m,
  origin (1000, 2000) in IPARAM, 18 triangles, a date record, variables
  VELOCITY U = 0 and BOTTOM = 2 + node; single or double precision.
- write_gmsh: 9 nodes on a 3 x 3 lattice of 1, 8 triangles, physical
  curves 1 "inflow" (y = 0), 2 (x = 2), 3 "outflow" (y = 2), 4 (x = 0); MSH
  4.1 (node tags unsorted) or 2.2.
- write_lonlat: an ADCIRC-like mesh, 25 nodes on a 5 x 5 lattice of 0.01
  degrees from (-80, 30), 32 triangles, depth_bed = -10 - node at the
  nodes; with or without CF attributes.
"""

import struct

from support import netcdf4

NET_FACES = [[0, 1, 5, 4], [4, 5, 9, 8], [1, 2, 6, 5], [5, 6, 10, 9], [2, 3, 7], [2, 7, 6], [6, 7, 11], [6, 11, 10]]
NET_EDGES = [(0, 1), (1, 2), (2, 3), (4, 5), (5, 6), (6, 7), (8, 9), (9, 10), (10, 11), (0, 4), (4, 8), (1, 5),
             (5, 9), (2, 6), (6, 10), (3, 7), (7, 11), (2, 7), (6, 11)]
NET_BOUNDARY = [(0, 1, 0), (1, 2, 0), (2, 3, 0), (3, 7, 2), (7, 11, 2), (8, 9, 0), (9, 10, 0), (10, 11, 0),
                (0, 4, 1), (4, 8, 1)]
FILL = -2147483647


def _mesh2d(ds, name):
    ds.createDimension(name + "_nNodes", 12)
    ds.createDimension(name + "_nFaces", 8)
    ds.createDimension("max_n%s_face_nodes" % name, 4)
    ds.createDimension(name + "_nEdges", len(NET_EDGES))
    ds.createDimension(name + "_nBoundaries", len(NET_BOUNDARY))
    if "Two" not in ds.dimensions:
        ds.createDimension("Two", 2)
    topology = ds.createVariable(name, "i4")
    topology.cf_role = "mesh_topology"
    topology.topology_dimension = 2
    topology.node_coordinates = "%s_node_x %s_node_y" % (name, name)
    topology.face_node_connectivity = name + "_face_nodes"
    topology.edge_node_connectivity = name + "_edge_nodes"
    topology.boundary_node_connectivity = name + "_bnd_nodes"
    topology.face_dimension = name + "_nFaces"
    topology.edge_dimension = name + "_nEdges"
    for axis, values in (("x", [10.0 * (n % 4) for n in range(12)]), ("y", [10.0 * (n // 4) for n in range(12)])):
        v = ds.createVariable("%s_node_%s" % (name, axis), "f8", (name + "_nNodes",))
        v.standard_name = "projection_%s_coordinate" % axis
        v.units = "m"
        v[:] = values
    faces = ds.createVariable(name + "_face_nodes", "i4", (name + "_nFaces", "max_n%s_face_nodes" % name),
                              fill_value=FILL)
    faces.cf_role = "face_node_connectivity"
    faces.start_index = 1
    faces[:] = [[n + 1 for n in f] + [FILL] * (4 - len(f)) for f in NET_FACES]
    edges = ds.createVariable(name + "_edge_nodes", "i4", (name + "_nEdges", "Two"))
    edges.start_index = 1
    edges[:] = [[a + 1, b + 1] for a, b in NET_EDGES]
    z = ds.createVariable(name + "_face_z", "f8", (name + "_nFaces",))
    z.location, z.mesh, z.units = "face", name, "m"
    z[:] = [20.0 + f for f in range(8)]
    z = ds.createVariable(name + "_node_z", "f8", (name + "_nNodes",))
    z.location, z.mesh = "node", name
    z[:] = [5.0 + n for n in range(12)]
    bnd = ds.createVariable(name + "_bnd_nodes", "i4", (name + "_nBoundaries", "Two"))
    bnd.cf_role = "boundary_node_connectivity"
    bnd.start_index = 1
    bnd[:] = [[a + 1, b + 1] for a, b, _ in NET_BOUNDARY]
    kind = ds.createVariable(name + "_bnd_type", "i4", (name + "_nBoundaries",))
    kind.flag_values = [1, 2]
    kind.flag_meanings = "inflow outflow"
    kind[:] = [t for _, _, t in NET_BOUNDARY]


def write_net_1d2d(path, second_2d=False):
    netCDF4 = netcdf4()
    with netCDF4.Dataset(str(path), "w") as ds:
        ds.Conventions = "CF-1.8 UGRID-1.0"
        ds.createDimension("mesh1d_nNodes", 3)
        m1 = ds.createVariable("mesh1d", "i4")
        m1.cf_role, m1.topology_dimension = "mesh_topology", 1
        m1.node_coordinates = "mesh1d_node_branch mesh1d_node_offset"
        ds.createVariable("mesh1d_node_branch", "i4", ("mesh1d_nNodes",))[:] = [1, 1, 1]
        ds.createVariable("mesh1d_node_offset", "f8", ("mesh1d_nNodes",))[:] = [0.0, 20.0, 40.0]
        net = ds.createVariable("network1d", "i4")
        net.cf_role, net.topology_dimension = "mesh_topology", 1
        _mesh2d(ds, "mesh2d")
        if second_2d:
            _mesh2d(ds, "mesh2d_refined")


def write_net_nodes_edges(path):
    netCDF4 = netcdf4()
    with netCDF4.Dataset(str(path), "w", format="NETCDF4") as ds:
        ds.createDimension("mesh2d_nNodes", 13)
        ds.createDimension("mesh2d_nEdges", len(NET_EDGES) + 1)
        ds.createDimension("two", 2)
        topology = ds.createVariable("mesh2d", "i4")
        topology.cf_role, topology.topology_dimension = "mesh_topology", 2
        topology.node_dimension, topology.edge_dimension = "mesh2d_nNodes", "mesh2d_nEdges"
        topology.edge_node_connectivity = "mesh2d_edge_nodes"
        topology.node_coordinates = "mesh2d_node_x mesh2d_node_y"
        edges = ds.createVariable("mesh2d_edge_nodes", "i8", ("mesh2d_nEdges", "two"), fill_value=-1)
        edges.cf_role, edges.start_index = "edge_node_connectivity", 0
        edges[:] = [list(e) for e in NET_EDGES] + [[3, 12]]
        for axis, values in (("x", [10.0 * (n % 4) for n in range(12)] + [40.0]),
                             ("y", [10.0 * (n // 4) for n in range(12)] + [0.0])):
            v = ds.createVariable("mesh2d_node_" + axis, "f8", ("mesh2d_nNodes",), fill_value=float("nan"))
            v.standard_name = "projection_%s_coordinate" % axis
            v[:] = values
        ds.createVariable("mesh2d_node_z", "f8", ("mesh2d_nNodes",))[:] = [float(n) for n in range(13)]


def _record(payload):
    return struct.pack(">i", len(payload)) + payload + struct.pack(">i", len(payload))


def _integers(values):
    return _record(struct.pack(">%di" % len(values), *values))


def write_selafin(path, double_precision=False):
    real = "d" if double_precision else "f"

    def reals(values):
        return _record(struct.pack(">%d%s" % (len(values), real), *values))

    title = ("%-72s%s" % ("DPSM TEST GEOMETRY", "SERAFIND" if double_precision else "SERAFIN ")).encode()
    triangles = []
    for j in range(3):
        for i in range(3):
            a = 1 + i + 4 * j
            b, c, d = a + 1, a + 5, a + 4
            triangles += [a, b, c, a, c, d]
    data = (_record(title) + _integers([2, 0]) + _record(b"VELOCITY U      M/S             ")
            + _record(b"BOTTOM          M               ") + _integers([1, 0, 1000, 2000, 0, 0, 1, 0, 0, 1])
            + _integers([2024, 6, 1, 0, 0, 0]) + _integers([18, 16, 3, 1]) + _integers(triangles)
            + _integers([0] * 16) + reals([10.0 * (n % 4) for n in range(16)])
            + reals([10.0 * (n // 4) for n in range(16)]) + reals([0.0]) + reals([0.0] * 16)
            + reals([2.0 + n for n in range(16)]))
    with open(str(path), "wb") as f:
        f.write(data)


GMSH_TRIANGLES = [[a, a + 1, a + 4, a, a + 4, a + 3][k:k + 3] for j in range(2) for i in range(2)
                  for a in [1 + i + 3 * j] for k in (0, 3)]
GMSH_LINES = [[(1, 2), (2, 3)], [(3, 6), (6, 9)], [(9, 8), (8, 7)], [(7, 4), (4, 1)]]


def write_gmsh(path, version=4):
    out = ["$MeshFormat", "%s 0 8" % ("4.1" if version == 4 else "2.2"), "$EndMeshFormat",
           "$PhysicalNames", "3", '1 1 "inflow"', '1 3 "outflow"', '2 10 "domain"', "$EndPhysicalNames"]
    if version == 4:
        out += ["$Entities", "4 4 1 0"]
        out += ["%d %g %g 0 0" % (p + 1, x, y) for p, (x, y) in enumerate([(0, 0), (2, 0), (2, 2), (0, 2)])]
        out += ["%d 0 0 0 2 2 0 1 %d 2 %d -%d" % (c + 1, c + 1, c + 1, (c + 1) % 4 + 1) for c in range(4)]
        out += ["1 0 0 0 2 2 0 1 10 4 1 2 3 4", "$EndEntities"]
        order = [5, 1, 2, 3, 4, 6, 7, 8, 9]
        out += ["$Nodes", "1 9 1 9", "2 1 0 9"] + [str(t) for t in order]
        out += ["%d %d 0" % ((t - 1) % 3, (t - 1) // 3) for t in order] + ["$EndNodes"]
        out += ["$Elements", "5 16 1 16"]
        tag = 1
        for c in range(4):
            out.append("1 %d 1 2" % (c + 1))
            for a, b in GMSH_LINES[c]:
                out.append("%d %d %d" % (tag, a, b))
                tag += 1
        out.append("2 1 2 8")
        for tri in GMSH_TRIANGLES:
            out.append("%d %d %d %d" % (tag, *tri))
            tag += 1
        out.append("$EndElements")
    else:
        out += ["$Nodes", "9"] + ["%d %d %d 0" % (n, (n - 1) % 3, (n - 1) // 3) for n in range(1, 10)]
        out += ["$EndNodes", "$Elements", "16"]
        tag = 1
        for c in range(4):
            for a, b in GMSH_LINES[c]:
                out.append("%d 1 2 %d %d %d %d" % (tag, c + 1, c + 1, a, b))
                tag += 1
        for tri in GMSH_TRIANGLES:
            out.append("%d 2 2 10 1 %d %d %d" % (tag, *tri))
            tag += 1
        out.append("$EndElements")
    with open(str(path), "w") as f:
        f.write("\n".join(out) + "\n")


def write_lonlat(path, attributes=True):
    netCDF4 = netcdf4()
    with netCDF4.Dataset(str(path), "w") as ds:
        ds.createDimension("nMesh2_node", 25)
        ds.createDimension("nMesh2_face", 32)
        ds.createDimension("Three", 3)
        topology = ds.createVariable("adcirc_mesh", "i4")
        topology.cf_role, topology.topology_dimension = "mesh_topology", 2
        topology.node_coordinates, topology.face_node_connectivity = "lon lat", "element"
        lon = ds.createVariable("lon", "f8", ("nMesh2_node",))
        lat = ds.createVariable("lat", "f8", ("nMesh2_node",))
        if attributes:
            lon.standard_name, lon.units = "longitude", "degrees_east"
            lat.standard_name, lat.units = "latitude", "degrees_north"
        lon[:] = [-80.0 + 0.01 * (n % 5) for n in range(25)]
        lat[:] = [30.0 + 0.01 * (n // 5) for n in range(25)]
        element = ds.createVariable("element", "i4", ("nMesh2_face", "Three"))
        element.start_index = 0
        rows = []
        for j in range(4):
            for i in range(4):
                a = i + 5 * j
                rows += [[a, a + 1, a + 6], [a, a + 6, a + 5]]
        element[:] = rows
        bed = ds.createVariable("depth_bed", "f8", ("nMesh2_node",))
        bed.location, bed.units = "node", "m"
        bed[:] = [-10.0 - n for n in range(25)]
        if attributes:  # ADCIRC's depth: positive down, said by its standard_name only
            depth = ds.createVariable("depth", "f8", ("nMesh2_node",))
            depth.location, depth.units, depth.standard_name = "node", "m", "depth_below_geoid"
            depth[:] = [10.0 + n for n in range(25)]
