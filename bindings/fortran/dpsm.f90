!> dpsm: the Fortran binding of the C API in include/dpsm/dpsm.h.
!>
!> One hand-written module over iso_c_binding:
!>
!>  - type(dpsm_grid) holds the C handle (a private type(c_ptr)); a grid is made
!>    by dpsm_create_1d / dpsm_create_2d / dpsm_create_axisymmetric (a mesh by
!>    dpsm_create_mesh / dpsm_create_graph / dpsm_create_dual_mesh) and released
!>    by dpsm_destroy, explicitly (there is no finalizer: copies of a
!>    type(dpsm_grid) share one handle, as copies of a C pointer do).
!>  - Every C function has a subroutine of the same name taking the C arguments
!>    in order (the grid first, outputs as arguments) and an optional
!>    `integer, intent(out) :: ierr` last. With ierr present it receives the
!>    status (DPSM_OK or a DPSM_ERR_* code); with ierr absent a failure stops the
!>    program (error stop) with the library's message.
!>  - dpsm_last_error, dpsm_status_string and dpsm_version_string are functions
!>    returning allocatable strings; dpsm_version_number returns an integer.
!>  - Sizes are integer(c_int64_t) as in C; every routine taking sizes also
!>    accepts integer(c_int32_t) (default integers). Block offsets i0, j0 are
!>    0-based, as in C.
!>  - The library's messages count from 1 on every grid this module creates
!>    or loads (dpsm_set_index_base): `kinds(3, 3) (cell i = 3, j = 3) = 9`,
!>    where a C host reads `kinds[12] (cell i = 2, j = 2) = 9`.
!>  - Arrays are assumed-shape: heights h(nx, ny) (or h(nx*ny); h(nx) on 1D and
!>    axisymmetric grids), real(c_double); cell kinds integer(c_int8_t). Their
!>    shape is checked against the grid (dpsm_get_shape) before C is called; a
!>    mismatch fails with DPSM_ERR_INVALID_SIZE and a message naming both shapes.
!>  - Meshes: the constructors take node and cell indices 1-based, as Fortran
!>    hosts hold them (0 for the domain edge in face_cells), and hand C the
!>    host's own arrays with start_index 1 (dpsm_create_mesh_indexed and the
!>    others, which take any start index, 0 or 1, themselves);
!>    dpsm_get_mesh_faces returns them as the mesh counts, 1-based. Pairs and
!>    triples are columns: node_xy(2, nnodes), face_cells(2, nfaces),
!>    triangle_nodes(3, ntriangles). On a mesh every per-cell array is
!>    h(ncells) (or h(ncells, 1)), face arrays (dpsm_get_face_fluxes' fx,
!>    dpsm_set_edge_kinds' kinds, the levels of DPSM_MESH_EDGE) hold nfaces
!>    values. The C library's messages on such a mesh count from 1, as the
!>    host does (see "meshes" below).
!>  - Paths (dpsm_save, dpsm_load) are default character strings; trailing
!>    blanks are dropped, so a path held in a longer variable may be passed.
!>  - Every \#define constant of dpsm.h is a parameter of the same name.
!>
!> tests/fortran/check_module.py fails the test suite when a function declared
!> with DPSM_API or a constant of dpsm.h has no counterpart here.
module dpsm
  use, intrinsic :: iso_c_binding, only: c_ptr, c_null_ptr, c_associated, c_f_pointer, c_int, c_int8_t, &
                                         c_int32_t, c_int64_t, c_double, c_char, c_size_t, c_null_char
  implicit none
  private

  ! ---- constants: every #define of dpsm.h ----------------------------------
  ! Status codes.
  !> Status codes: DPSM_OK, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_OK = 0
  !> Status codes: DPSM_ERR_NULL_POINTER, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_NULL_POINTER = 1
  !> Status codes: DPSM_ERR_INVALID_VALUE, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_INVALID_VALUE = 2
  !> Status codes: DPSM_ERR_INVALID_SIZE, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_INVALID_SIZE = 3
  !> Status codes: DPSM_ERR_UNKNOWN_ENUM, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_UNKNOWN_ENUM = 4
  !> Status codes: DPSM_ERR_NOT_APPLICABLE, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_NOT_APPLICABLE = 5
  !> Status codes: DPSM_ERR_WORK_LIMIT, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_WORK_LIMIT = 6
  !> Status codes: DPSM_ERR_OUT_OF_MEMORY, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_OUT_OF_MEMORY = 7
  !> Status codes: DPSM_ERR_INTERNAL, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_INTERNAL = 8
  !> Status codes: DPSM_ERR_IO, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_IO = 9
  !> Status codes: DPSM_ERR_BAD_FILE, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_ERR_BAD_FILE = 10
  ! Sides of the domain.
  !> Sides of the domain: DPSM_XMIN, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_XMIN = 0
  !> Sides of the domain: DPSM_XMAX, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_XMAX = 1
  !> Sides of the domain: DPSM_YMIN, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_YMIN = 2
  !> Sides of the domain: DPSM_YMAX, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_YMAX = 3
  !> Sides of the domain: DPSM_MESH_EDGE, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_MESH_EDGE = 4
  ! Grid kinds (dpsm_get_grid_kind).
  !> Grid kinds (dpsm_get_grid_kind): DPSM_GRID_1D, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_GRID_1D = 1
  !> Grid kinds (dpsm_get_grid_kind): DPSM_GRID_AXISYMMETRIC, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_GRID_AXISYMMETRIC = 2
  !> Grid kinds (dpsm_get_grid_kind): DPSM_GRID_2D, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_GRID_2D = 3
  !> Grid kinds (dpsm_get_grid_kind): DPSM_GRID_MESH, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_GRID_MESH = 4
  ! Boundary kinds.
  !> Boundary kinds: DPSM_OPEN, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_OPEN = 0
  !> Boundary kinds: DPSM_WALL, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_WALL = 1
  ! Schemes.
  !> Schemes: DPSM_SCHEME_PAIRWISE, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_SCHEME_PAIRWISE = 0
  !> Schemes: DPSM_SCHEME_ISOTROPIC, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_SCHEME_ISOTROPIC = 1
  ! Relaxations (dpsm_set_relaxation).
  !> Relaxations (dpsm_set_relaxation): DPSM_RELAX_TIME_ACCURATE, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_RELAX_TIME_ACCURATE = 0
  !> Relaxations (dpsm_set_relaxation): DPSM_RELAX_TO_REST, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_RELAX_TO_REST = 1
  !> Relaxations (dpsm_set_relaxation): DPSM_RELAX_AUTO, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_RELAX_AUTO = 2
  !> Relaxations (dpsm_set_relaxation): DPSM_RELAX_LOCAL_STEPS, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_RELAX_LOCAL_STEPS = 3
  ! Cell kinds (the values of an integer(c_int8_t) kinds array).
  !> Cell kinds (the values of an integer(c_int8_t) kinds array): DPSM_CELL_SAND, as in dpsm.h.
  integer(c_int8_t), parameter, public :: DPSM_CELL_SAND = 0_c_int8_t
  !> Cell kinds (the values of an integer(c_int8_t) kinds array): DPSM_CELL_WALL, as in dpsm.h.
  integer(c_int8_t), parameter, public :: DPSM_CELL_WALL = 1_c_int8_t
  !> Cell kinds (the values of an integer(c_int8_t) kinds array): DPSM_CELL_OPEN, as in dpsm.h.
  integer(c_int8_t), parameter, public :: DPSM_CELL_OPEN = 2_c_int8_t
  ! Mass quantities.
  !> Mass quantities: DPSM_MASS_TOTAL, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_MASS_TOTAL = 0
  !> Mass quantities: DPSM_MASS_SOURCED, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_MASS_SOURCED = 1
  !> Mass quantities: DPSM_MASS_EXTERNAL, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_MASS_EXTERNAL = 2
  !> Mass quantities: DPSM_MASS_OUTFLOW, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_MASS_OUTFLOW = 3
  !> Mass quantities: DPSM_MASS_UNMET, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_MASS_UNMET = 4
  ! Step information.
  !> Step information: DPSM_INFO_SUBSTEPS, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_SUBSTEPS = 0
  !> Step information: DPSM_INFO_TIME_INTEGRATED, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_TIME_INTEGRATED = 1
  !> Step information: DPSM_INFO_AT_REST, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_AT_REST = 2
  !> Step information: DPSM_INFO_MAX_EXCESS_SLOPE, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_MAX_EXCESS_SLOPE = 3
  !> Step information: DPSM_INFO_CELL_UPDATES, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_CELL_UPDATES = 4
  !> Step information: DPSM_INFO_RANK_CELL_UPDATES, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_RANK_CELL_UPDATES = 5
  !> Step information: DPSM_INFO_MESSAGES_SENT, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_MESSAGES_SENT = 6
  !> Step information: DPSM_INFO_BYTES_SENT, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_BYTES_SENT = 7
  !> Step information: DPSM_INFO_SUBSTEPS_PER_EXCHANGE, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_SUBSTEPS_PER_EXCHANGE = 8
  !> Step information: DPSM_INFO_SUBSTEPS_EVALUATED, as in dpsm.h.
  integer(c_int), parameter, public :: DPSM_INFO_SUBSTEPS_EVALUATED = 9
  ! Defaults.
  !> Defaults: DPSM_DEFAULT_REPOSE_ANGLE, as in dpsm.h.
  real(c_double), parameter, public :: DPSM_DEFAULT_REPOSE_ANGLE = 0.52359877559829887_c_double
  !> Defaults: DPSM_DEFAULT_MOBILITY, as in dpsm.h.
  real(c_double), parameter, public :: DPSM_DEFAULT_MOBILITY = 1.0_c_double
  !> Defaults: DPSM_DEFAULT_REST_TOLERANCE, as in dpsm.h.
  real(c_double), parameter, public :: DPSM_DEFAULT_REST_TOLERANCE = 1e-6_c_double
  !> Defaults: DPSM_DEFAULT_MAX_SUBSTEPS, as in dpsm.h.
  integer(c_int64_t), parameter, public :: DPSM_DEFAULT_MAX_SUBSTEPS = 10000000_c_int64_t
  !> Defaults: DPSM_DEFAULT_FLUX_EXPONENT, as in dpsm.h.
  real(c_double), parameter, public :: DPSM_DEFAULT_FLUX_EXPONENT = 1.0_c_double
  !> Defaults: DPSM_MAX_FLUX_EXPONENT, as in dpsm.h.
  real(c_double), parameter, public :: DPSM_MAX_FLUX_EXPONENT = 2.0_c_double

  ! The version of the headers this module was built against (dpsm_version.h).
  ! DPSM_VERSION_NUMBER and DPSM_VERSION_STRING are DPSM_HEADER_VERSION_NUMBER
  ! and DPSM_HEADER_VERSION_STRING here: Fortran names ignore case, and the
  ! functions dpsm_version_number() and dpsm_version_string() take the C names.
  include 'dpsm_version.inc'

  ! ---- the grid ------------------------------------------------------------
  !> Messages of failures found on the Fortran side (a wrong array shape),
  !> kept with the handle so that dpsm_last_error(g) reports them.
  type :: grid_state
    character(len=:), allocatable :: message
  end type grid_state

  !> Messages of failures found on the Fortran side when there is no grid to
  !> keep them (a mesh constructor given arrays of the wrong size), for
  !> dpsm_last_error() without a grid. no_grid_snapshot is what C's
  !> dpsm_last_error(NULL) said at that moment: once C reports another
  !> failure without a grid, that newer message is the one returned. Unlike
  !> C's, which is kept per thread, these are shared by the threads of a
  !> program: read the message in the thread that failed, before another
  !> thread fails a create.
  character(len=:), allocatable :: no_grid_message, no_grid_snapshot

  !> A dpsm grid: the C handle. Default-initialized to no grid (C's NULL).
  type, public :: dpsm_grid
    private
    !> The C handle (C's NULL when there is no grid).
    type(c_ptr) :: ptr = c_null_ptr
    !> The messages of failures found on the Fortran side, kept with the handle.
    type(grid_state), pointer :: state => null()
  end type dpsm_grid

  ! ---- the public procedures: one per C function ---------------------------
  public :: dpsm_create_1d, dpsm_create_2d, dpsm_create_axisymmetric, dpsm_destroy
  public :: dpsm_set_repose_angle, dpsm_set_mobility, dpsm_set_scheme, dpsm_set_relaxation, dpsm_set_boundary
  public :: dpsm_set_cell_kinds, dpsm_set_heights, dpsm_get_heights
  public :: dpsm_set_heights_region, dpsm_add_heights_region, dpsm_get_heights_region
  public :: dpsm_set_source, dpsm_stable_dt, dpsm_step, dpsm_get_mass, dpsm_get_step_info
  public :: dpsm_get_shape, dpsm_get_grid_kind, dpsm_set_rest_tolerance, dpsm_set_max_substeps, dpsm_set_threads
  public :: dpsm_get_threads
  public :: dpsm_set_index_base
  public :: dpsm_set_bedrock, dpsm_set_repose_angle_field, dpsm_set_flux_exponent, dpsm_set_static_angle
  public :: dpsm_set_side_levels, dpsm_get_side_outflow, dpsm_set_face_flux_recording, dpsm_get_face_fluxes
  public :: dpsm_save, dpsm_load
  public :: dpsm_last_error, dpsm_status_string, dpsm_version_string, dpsm_version_number
  public :: dpsm_create_mesh, dpsm_create_graph, dpsm_create_dual_mesh
  public :: dpsm_create_mesh_indexed, dpsm_create_graph_indexed, dpsm_create_dual_mesh_indexed
  public :: dpsm_get_face_count, dpsm_get_mesh_faces, dpsm_set_edge_kinds
  public :: dpsm_create_mesh_geographic, dpsm_create_dual_mesh_geographic, dpsm_get_cell_centres
  ! Not in C: .true. when g holds a grid (its handle is not NULL).
  public :: dpsm_associated
  ! Not in C: for companion modules (dpsm_mpi) whose own C constructors make
  ! the handle: stores it in g as the dpsm_create_* routines do.
  public :: dpsm_adopt_handle

  interface dpsm_create_1d
    module procedure create_1d_i64, create_1d_i32
  end interface dpsm_create_1d
  interface dpsm_create_2d
    module procedure create_2d_i64, create_2d_i32
  end interface dpsm_create_2d
  interface dpsm_create_axisymmetric
    module procedure create_axisymmetric_i64, create_axisymmetric_i32
  end interface dpsm_create_axisymmetric
  interface dpsm_create_mesh
    module procedure create_mesh_i64, create_mesh_i32
  end interface dpsm_create_mesh
  interface dpsm_create_graph
    module procedure create_graph_i64, create_graph_i32
  end interface dpsm_create_graph
  interface dpsm_create_dual_mesh
    module procedure create_dual_mesh_i64, create_dual_mesh_i32
  end interface dpsm_create_dual_mesh
  interface dpsm_create_mesh_indexed
    module procedure create_mesh_indexed_i64, create_mesh_indexed_i32
  end interface dpsm_create_mesh_indexed
  interface dpsm_create_graph_indexed
    module procedure create_graph_indexed_i64, create_graph_indexed_i32
  end interface dpsm_create_graph_indexed
  interface dpsm_create_dual_mesh_indexed
    module procedure create_dual_mesh_indexed_i64, create_dual_mesh_indexed_i32
  end interface dpsm_create_dual_mesh_indexed
  interface dpsm_create_mesh_geographic
    module procedure create_mesh_geographic_i64, create_mesh_geographic_i32
  end interface dpsm_create_mesh_geographic
  interface dpsm_create_dual_mesh_geographic
    module procedure create_dual_mesh_geographic_i64, create_dual_mesh_geographic_i32
  end interface dpsm_create_dual_mesh_geographic
  interface dpsm_get_face_count
    module procedure get_face_count_i64, get_face_count_i32
  end interface dpsm_get_face_count
  interface dpsm_get_mesh_faces
    module procedure get_mesh_faces_i64, get_mesh_faces_i32
  end interface dpsm_get_mesh_faces
  interface dpsm_set_edge_kinds
    module procedure set_edge_kinds_r1, set_edge_kinds_none
  end interface dpsm_set_edge_kinds
  interface dpsm_set_cell_kinds
    module procedure set_cell_kinds_r1, set_cell_kinds_r2, set_cell_kinds_none
  end interface dpsm_set_cell_kinds
  interface dpsm_set_heights
    module procedure set_heights_r1, set_heights_r2
  end interface dpsm_set_heights
  interface dpsm_get_heights
    module procedure get_heights_r1, get_heights_r2
  end interface dpsm_get_heights
  interface dpsm_set_heights_region
    module procedure set_heights_region_i64_r1, set_heights_region_i64_r2, &
                     set_heights_region_i32_r1, set_heights_region_i32_r2
  end interface dpsm_set_heights_region
  interface dpsm_add_heights_region
    module procedure add_heights_region_i64_r1, add_heights_region_i64_r2, &
                     add_heights_region_i32_r1, add_heights_region_i32_r2
  end interface dpsm_add_heights_region
  interface dpsm_get_heights_region
    module procedure get_heights_region_i64_r1, get_heights_region_i64_r2, &
                     get_heights_region_i32_r1, get_heights_region_i32_r2
  end interface dpsm_get_heights_region
  interface dpsm_set_source
    module procedure set_source_r1, set_source_r2, set_source_none
  end interface dpsm_set_source
  interface dpsm_set_bedrock
    module procedure set_bedrock_r1, set_bedrock_r2, set_bedrock_none
  end interface dpsm_set_bedrock
  interface dpsm_set_repose_angle_field
    module procedure set_repose_angle_field_r1, set_repose_angle_field_r2, set_repose_angle_field_none
  end interface dpsm_set_repose_angle_field
  interface dpsm_get_shape
    module procedure get_shape_i64, get_shape_i32
  end interface dpsm_get_shape
  interface dpsm_set_side_levels
    module procedure set_side_levels_r1, set_side_levels_none
  end interface dpsm_set_side_levels
  interface dpsm_get_face_fluxes
    module procedure get_face_fluxes_r1, get_face_fluxes_r2
  end interface dpsm_get_face_fluxes
  interface dpsm_set_max_substeps
    module procedure set_max_substeps_i64, set_max_substeps_i32
  end interface dpsm_set_max_substeps

  ! ---- the C functions -----------------------------------------------------
  interface
    integer(c_int) function c_dpsm_create_1d(nx, dx, out) bind(C, name='dpsm_create_1d')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int64_t), value :: nx
      real(c_double), value :: dx
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_1d

    integer(c_int) function c_dpsm_create_2d(nx, ny, dx, dy, out) bind(C, name='dpsm_create_2d')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int64_t), value :: nx, ny
      real(c_double), value :: dx, dy
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_2d

    integer(c_int) function c_dpsm_create_axisymmetric(nr, dr, out) bind(C, name='dpsm_create_axisymmetric')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int64_t), value :: nr
      real(c_double), value :: dr
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_axisymmetric

    ! C's constructors from 0; the module calls the _indexed ones below.
    integer(c_int) function c_dpsm_create_mesh(nnodes, node_xy, ncells, cell_start, cell_nodes, out) &
        bind(C, name='dpsm_create_mesh')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int64_t), value :: nnodes, ncells
      real(c_double), intent(in) :: node_xy(*)
      integer(c_int64_t), intent(in) :: cell_start(*), cell_nodes(*) ! 0-based
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_mesh

    integer(c_int) function c_dpsm_create_graph(ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, &
                                                out) bind(C, name='dpsm_create_graph')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int64_t), value :: ncells, nfaces
      real(c_double), intent(in) :: cell_xy(*), cell_area(*), face_xy(*), face_length(*)
      integer(c_int64_t), intent(in) :: face_cells(*) ! 0-based, -1 on the domain edge
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_graph

    integer(c_int) function c_dpsm_create_dual_mesh(nnodes, node_xy, ntriangles, triangle_nodes, out) &
        bind(C, name='dpsm_create_dual_mesh')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int64_t), value :: nnodes, ntriangles
      real(c_double), intent(in) :: node_xy(*)
      integer(c_int64_t), intent(in) :: triangle_nodes(*) ! 0-based
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_dual_mesh

    integer(c_int) function c_dpsm_create_mesh_indexed(start_index, nnodes, node_xy, ncells, cell_start, cell_nodes, &
                                                       out) bind(C, name='dpsm_create_mesh_indexed')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int), value :: start_index
      integer(c_int64_t), value :: nnodes, ncells
      real(c_double), intent(in) :: node_xy(*)
      integer(c_int64_t), intent(in) :: cell_start(*), cell_nodes(*) ! from start_index
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_mesh_indexed

    integer(c_int) function c_dpsm_create_graph_indexed(start_index, ncells, cell_xy, cell_area, nfaces, face_cells, &
                                                        face_xy, face_length, out) &
        bind(C, name='dpsm_create_graph_indexed')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int), value :: start_index
      integer(c_int64_t), value :: ncells, nfaces
      real(c_double), intent(in) :: cell_xy(*), cell_area(*), face_xy(*), face_length(*)
      integer(c_int64_t), intent(in) :: face_cells(*) ! from start_index, start_index-1 on the domain edge
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_graph_indexed

    integer(c_int) function c_dpsm_create_dual_mesh_indexed(start_index, nnodes, node_xy, ntriangles, triangle_nodes, &
                                                            out) bind(C, name='dpsm_create_dual_mesh_indexed')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int), value :: start_index
      integer(c_int64_t), value :: nnodes, ntriangles
      real(c_double), intent(in) :: node_xy(*)
      integer(c_int64_t), intent(in) :: triangle_nodes(*) ! from start_index
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_dual_mesh_indexed

    integer(c_int) function c_dpsm_create_mesh_geographic(start_index, nnodes, node_lonlat, ncells, cell_start, &
                                                          cell_nodes, out) bind(C, name='dpsm_create_mesh_geographic')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int), value :: start_index
      integer(c_int64_t), value :: nnodes, ncells
      real(c_double), intent(in) :: node_lonlat(*)
      integer(c_int64_t), intent(in) :: cell_start(*), cell_nodes(*) ! from start_index
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_mesh_geographic

    integer(c_int) function c_dpsm_create_dual_mesh_geographic(start_index, nnodes, node_lonlat, ntriangles, &
                                                               triangle_nodes, out) &
        bind(C, name='dpsm_create_dual_mesh_geographic')
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int), value :: start_index
      integer(c_int64_t), value :: nnodes, ntriangles
      real(c_double), intent(in) :: node_lonlat(*)
      integer(c_int64_t), intent(in) :: triangle_nodes(*) ! from start_index
      type(c_ptr), intent(out) :: out
    end function c_dpsm_create_dual_mesh_geographic

    integer(c_int) function c_dpsm_get_cell_centres(g, cell_xy, cell_area) bind(C, name='dpsm_get_cell_centres')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), intent(out), optional :: cell_xy(*) ! absent: NULL
      real(c_double), intent(out), optional :: cell_area(*) ! absent: NULL
    end function c_dpsm_get_cell_centres

    integer(c_int) function c_dpsm_get_face_count(g, nfaces) bind(C, name='dpsm_get_face_count')
      import :: c_int, c_int64_t, c_ptr
      type(c_ptr), value :: g
      integer(c_int64_t), intent(out) :: nfaces
    end function c_dpsm_get_face_count

    integer(c_int) function c_dpsm_get_mesh_faces(g, face_cells) bind(C, name='dpsm_get_mesh_faces')
      import :: c_int, c_int64_t, c_ptr
      type(c_ptr), value :: g
      integer(c_int64_t), intent(inout) :: face_cells(*) ! from the mesh's start index, one less on the domain edge
    end function c_dpsm_get_mesh_faces

    integer(c_int) function c_dpsm_set_edge_kinds(g, kinds) bind(C, name='dpsm_set_edge_kinds')
      import :: c_int, c_int8_t, c_ptr
      type(c_ptr), value :: g
      integer(c_int8_t), intent(in), optional :: kinds(*) ! absent: NULL
    end function c_dpsm_set_edge_kinds

    subroutine c_dpsm_destroy(g) bind(C, name='dpsm_destroy')
      import :: c_ptr
      type(c_ptr), value :: g
    end subroutine c_dpsm_destroy

    integer(c_int) function c_dpsm_set_repose_angle(g, theta_radians) bind(C, name='dpsm_set_repose_angle')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), value :: theta_radians
    end function c_dpsm_set_repose_angle

    integer(c_int) function c_dpsm_set_mobility(g, nu) bind(C, name='dpsm_set_mobility')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), value :: nu
    end function c_dpsm_set_mobility

    integer(c_int) function c_dpsm_set_scheme(g, scheme) bind(C, name='dpsm_set_scheme')
      import :: c_int, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: scheme
    end function c_dpsm_set_scheme

    integer(c_int) function c_dpsm_set_relaxation(g, relaxation) bind(C, name='dpsm_set_relaxation')
      import :: c_int, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: relaxation
    end function c_dpsm_set_relaxation

    integer(c_int) function c_dpsm_set_boundary(g, side, kind) bind(C, name='dpsm_set_boundary')
      import :: c_int, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: side, kind
    end function c_dpsm_set_boundary

    integer(c_int) function c_dpsm_set_cell_kinds(g, kinds) bind(C, name='dpsm_set_cell_kinds')
      import :: c_int, c_int8_t, c_ptr
      type(c_ptr), value :: g
      integer(c_int8_t), intent(in), optional :: kinds(*) ! absent: NULL
    end function c_dpsm_set_cell_kinds

    integer(c_int) function c_dpsm_set_heights(g, h) bind(C, name='dpsm_set_heights')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), intent(in) :: h(*)
    end function c_dpsm_set_heights

    integer(c_int) function c_dpsm_get_heights(g, h) bind(C, name='dpsm_get_heights')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), intent(inout) :: h(*)
    end function c_dpsm_get_heights

    integer(c_int) function c_dpsm_set_heights_region(g, i0, j0, ni, nj, h) bind(C, name='dpsm_set_heights_region')
      import :: c_int, c_int64_t, c_double, c_ptr
      type(c_ptr), value :: g
      integer(c_int64_t), value :: i0, j0, ni, nj
      real(c_double), intent(in) :: h(*)
    end function c_dpsm_set_heights_region

    integer(c_int) function c_dpsm_add_heights_region(g, i0, j0, ni, nj, dh) bind(C, name='dpsm_add_heights_region')
      import :: c_int, c_int64_t, c_double, c_ptr
      type(c_ptr), value :: g
      integer(c_int64_t), value :: i0, j0, ni, nj
      real(c_double), intent(in) :: dh(*)
    end function c_dpsm_add_heights_region

    integer(c_int) function c_dpsm_get_heights_region(g, i0, j0, ni, nj, h) bind(C, name='dpsm_get_heights_region')
      import :: c_int, c_int64_t, c_double, c_ptr
      type(c_ptr), value :: g
      integer(c_int64_t), value :: i0, j0, ni, nj
      real(c_double), intent(inout) :: h(*)
    end function c_dpsm_get_heights_region

    integer(c_int) function c_dpsm_set_source(g, q) bind(C, name='dpsm_set_source')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), intent(in), optional :: q(*) ! absent: NULL
    end function c_dpsm_set_source

    integer(c_int) function c_dpsm_stable_dt(g, dt) bind(C, name='dpsm_stable_dt')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), intent(out) :: dt
    end function c_dpsm_stable_dt

    integer(c_int) function c_dpsm_step(g, dt) bind(C, name='dpsm_step')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), value :: dt
    end function c_dpsm_step

    integer(c_int) function c_dpsm_get_mass(g, quantity, value) bind(C, name='dpsm_get_mass')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: quantity
      real(c_double), intent(out) :: value
    end function c_dpsm_get_mass

    integer(c_int) function c_dpsm_get_step_info(g, item, value) bind(C, name='dpsm_get_step_info')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: item
      real(c_double), intent(out) :: value
    end function c_dpsm_get_step_info

    integer(c_int) function c_dpsm_get_shape(g, nx, ny) bind(C, name='dpsm_get_shape')
      import :: c_int, c_int64_t, c_ptr
      type(c_ptr), value :: g
      integer(c_int64_t), intent(out) :: nx, ny
    end function c_dpsm_get_shape

    integer(c_int) function c_dpsm_set_rest_tolerance(g, tol) bind(C, name='dpsm_set_rest_tolerance')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), value :: tol
    end function c_dpsm_set_rest_tolerance

    integer(c_int) function c_dpsm_set_max_substeps(g, n) bind(C, name='dpsm_set_max_substeps')
      import :: c_int, c_int64_t, c_ptr
      type(c_ptr), value :: g
      integer(c_int64_t), value :: n
    end function c_dpsm_set_max_substeps

    integer(c_int) function c_dpsm_set_threads(g, n) bind(C, name='dpsm_set_threads')
      import :: c_int, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: n
    end function c_dpsm_set_threads

    integer(c_int) function c_dpsm_get_threads(g, n) bind(C, name='dpsm_get_threads')
      import :: c_int, c_ptr
      type(c_ptr), value :: g
      integer(c_int), intent(out) :: n
    end function c_dpsm_get_threads

    integer(c_int) function c_dpsm_get_grid_kind(g, kind) bind(C, name='dpsm_get_grid_kind')
      import :: c_int, c_ptr
      type(c_ptr), value :: g
      integer(c_int), intent(out) :: kind
    end function c_dpsm_get_grid_kind

    integer(c_int) function c_dpsm_set_index_base(g, base) bind(C, name='dpsm_set_index_base')
      import :: c_int, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: base
    end function c_dpsm_set_index_base

    integer(c_int) function c_dpsm_set_bedrock(g, zb) bind(C, name='dpsm_set_bedrock')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), intent(in), optional :: zb(*) ! absent: NULL
    end function c_dpsm_set_bedrock

    integer(c_int) function c_dpsm_set_repose_angle_field(g, theta_radians) &
        bind(C, name='dpsm_set_repose_angle_field')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), intent(in), optional :: theta_radians(*) ! absent: NULL
    end function c_dpsm_set_repose_angle_field

    integer(c_int) function c_dpsm_set_flux_exponent(g, p) bind(C, name='dpsm_set_flux_exponent')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), value :: p
    end function c_dpsm_set_flux_exponent

    integer(c_int) function c_dpsm_set_static_angle(g, radians) bind(C, name='dpsm_set_static_angle')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), value :: radians
    end function c_dpsm_set_static_angle

    integer(c_int) function c_dpsm_set_side_levels(g, side, levels) bind(C, name='dpsm_set_side_levels')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: side
      real(c_double), intent(in), optional :: levels(*) ! absent: NULL
    end function c_dpsm_set_side_levels

    integer(c_int) function c_dpsm_get_side_outflow(g, side, value) bind(C, name='dpsm_get_side_outflow')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: side
      real(c_double), intent(out) :: value
    end function c_dpsm_get_side_outflow

    integer(c_int) function c_dpsm_set_face_flux_recording(g, on) bind(C, name='dpsm_set_face_flux_recording')
      import :: c_int, c_ptr
      type(c_ptr), value :: g
      integer(c_int), value :: on
    end function c_dpsm_set_face_flux_recording

    integer(c_int) function c_dpsm_get_face_fluxes(g, fx, fy) bind(C, name='dpsm_get_face_fluxes')
      import :: c_int, c_double, c_ptr
      type(c_ptr), value :: g
      real(c_double), intent(out) :: fx(*)
      real(c_double), intent(out), optional :: fy(*) ! absent: NULL
    end function c_dpsm_get_face_fluxes

    integer(c_int) function c_dpsm_save(g, path) bind(C, name='dpsm_save')
      import :: c_int, c_char, c_ptr
      type(c_ptr), value :: g
      character(kind=c_char), intent(in) :: path(*) ! NUL-terminated
    end function c_dpsm_save

    integer(c_int) function c_dpsm_load(path, out) bind(C, name='dpsm_load')
      import :: c_int, c_char, c_ptr
      character(kind=c_char), intent(in) :: path(*) ! NUL-terminated
      type(c_ptr), intent(out) :: out
    end function c_dpsm_load

    type(c_ptr) function c_dpsm_last_error(g) bind(C, name='dpsm_last_error')
      import :: c_ptr
      type(c_ptr), value :: g
    end function c_dpsm_last_error

    type(c_ptr) function c_dpsm_status_string(status) bind(C, name='dpsm_status_string')
      import :: c_ptr, c_int
      integer(c_int), value :: status
    end function c_dpsm_status_string

    type(c_ptr) function c_dpsm_version_string() bind(C, name='dpsm_version_string')
      import :: c_ptr
    end function c_dpsm_version_string

    integer(c_int) function c_dpsm_version_number() bind(C, name='dpsm_version_number')
      import :: c_int
    end function c_dpsm_version_number

    integer(c_size_t) function c_strlen(s) bind(C, name='strlen')
      import :: c_size_t, c_ptr
      type(c_ptr), value :: s
    end function c_strlen
  end interface

contains

  ! ==== helpers ==============================================================

  !> A NUL-terminated C string as a Fortran string ('' for NULL).
  function from_c_string(p) result(s)
    type(c_ptr), intent(in) :: p
    character(len=:), allocatable :: s
    character(kind=c_char), pointer :: chars(:)
    integer :: i, n
    if (.not. c_associated(p)) then
      s = ''
      return
    end if
    n = int(c_strlen(p))
    call c_f_pointer(p, chars, [n])
    allocate (character(len=n) :: s)
    do i = 1, n
      s(i:i) = chars(i)
    end do
  end function from_c_string

  function itoa(i) result(s)
    integer(c_int64_t), intent(in) :: i
    character(len=:), allocatable :: s
    character(len=24) :: buffer
    write (buffer, '(i0)') i
    s = trim(buffer)
  end function itoa

  function shape_string(s) result(r)
    integer, intent(in) :: s(:)
    character(len=:), allocatable :: r
    integer :: k
    r = '('
    do k = 1, size(s)
      if (k > 1) r = r//', '
      r = r//itoa(int(s(k), c_int64_t))
    end do
    r = r//')'
  end function shape_string

  !> Forgets a message of the Fortran side: called as every call on g begins.
  subroutine clear_message(g)
    type(dpsm_grid), intent(in) :: g
    if (associated(g%state)) then
      if (allocated(g%state%message)) deallocate (g%state%message)
    end if
  end subroutine clear_message

  !> Records a failure found on the Fortran side, for dpsm_last_error(g).
  subroutine set_message(g, message)
    type(dpsm_grid), intent(in) :: g
    character(len=*), intent(in) :: message
    if (associated(g%state)) g%state%message = message
  end subroutine set_message

  !> Hands a status to the caller: into ierr when present; otherwise a failure
  !> stops the program with the message of the failed call.
  subroutine finish(status, ierr, where, g)
    integer(c_int), intent(in) :: status
    integer, intent(out), optional :: ierr
    character(len=*), intent(in) :: where
    type(dpsm_grid), intent(in), optional :: g
    character(len=:), allocatable :: message
    if (present(ierr)) then
      ierr = int(status)
      return
    end if
    if (status == DPSM_OK) return
    message = where//' failed: '//dpsm_status_string(status)//': '//dpsm_last_error(g)
    error stop message
  end subroutine finish

  !> Reads the grid's shape and compares it with an array's: DPSM_OK, the
  !> status of a failed dpsm_get_shape, or DPSM_ERR_INVALID_SIZE with a message.
  function check_grid_shape(g, where, name, array_shape) result(status)
    type(dpsm_grid), intent(in) :: g
    character(len=*), intent(in) :: where, name
    integer, intent(in) :: array_shape(:)
    integer(c_int) :: status
    status = check_grid_shape_plus(g, where, name, 0, 0, array_shape)
  end function check_grid_shape

  !> As check_grid_shape, for an array of (nx + extra_x) by (ny + extra_y)
  !> values, one per face of a kind: the x faces are (nx+1, ny), the y faces
  !> (nx, ny+1).
  function check_grid_shape_plus(g, where, name, extra_x, extra_y, array_shape) result(status)
    type(dpsm_grid), intent(in) :: g
    character(len=*), intent(in) :: where, name
    integer, intent(in) :: extra_x, extra_y
    integer, intent(in) :: array_shape(:)
    integer(c_int) :: status
    integer(c_int64_t) :: nx, ny, ni, nj
    character(len=:), allocatable :: along_x, along_y
    logical :: ok
    status = c_dpsm_get_shape(g%ptr, nx, ny)
    if (status /= DPSM_OK) return
    ni = nx + extra_x
    nj = ny + extra_y
    if (size(array_shape) == 1) then
      ok = int(array_shape(1), c_int64_t) == ni*nj
    else
      ok = int(array_shape(1), c_int64_t) == ni .and. int(array_shape(2), c_int64_t) == nj
    end if
    if (ok) return
    status = DPSM_ERR_INVALID_SIZE
    along_x = plus_one('nx', extra_x)
    along_y = plus_one('ny', extra_y)
    call set_message(g, where//': '//name//' has shape '//shape_string(array_shape)// &
                     ' but the grid has nx = '//itoa(nx)//', ny = '//itoa(ny)// &
                     ': pass '//name//'('//along_x//', '//along_y//') or '//name//'('// &
                     factor(along_x, extra_x)//'*'//factor(along_y, extra_y)//')')
  end function check_grid_shape_plus

  !> 'nx' or 'nx+1', for a message.
  function plus_one(n, extra) result(s)
    character(len=*), intent(in) :: n
    integer, intent(in) :: extra
    character(len=:), allocatable :: s
    s = n
    if (extra > 0) s = n//'+1'
  end function plus_one

  !> A sum in parentheses, as a factor in a message.
  function factor(term, extra) result(s)
    character(len=*), intent(in) :: term
    integer, intent(in) :: extra
    character(len=:), allocatable :: s
    s = term
    if (extra > 0) s = '('//term//')'
  end function factor

  !> As check_grid_shape, for a block of ni by nj cells.
  function check_block_shape(g, where, name, ni, nj, array_shape) result(status)
    type(dpsm_grid), intent(in) :: g
    character(len=*), intent(in) :: where, name
    integer(c_int64_t), intent(in) :: ni, nj
    integer, intent(in) :: array_shape(:)
    integer(c_int) :: status
    integer(c_int64_t) :: nx, ny
    logical :: ok
    ! A NULL handle fails here first, with the library's message.
    status = c_dpsm_get_shape(g%ptr, nx, ny)
    if (status /= DPSM_OK) return
    if (size(array_shape) == 1) then
      ok = int(array_shape(1), c_int64_t) == ni*nj
    else
      ok = int(array_shape(1), c_int64_t) == ni .and. int(array_shape(2), c_int64_t) == nj
    end if
    if (ok) return
    status = DPSM_ERR_INVALID_SIZE
    call set_message(g, where//': '//name//' has shape '//shape_string(array_shape)// &
                     ' but the block has ni = '//itoa(ni)//', nj = '//itoa(nj)// &
                     ': pass '//name//'(ni, nj) or '//name//'(ni*nj)')
  end function check_block_shape

  !> A size of default kind as c_int64_t, for the integer(c_int32_t) variants.
  elemental function i64(i) result(r)
    integer(c_int32_t), intent(in) :: i
    integer(c_int64_t) :: r
    r = int(i, c_int64_t)
  end function i64

  ! ==== not in C =============================================================

  !> .true. when g holds a grid (made by a create call and not destroyed).
  logical function dpsm_associated(g)
    type(dpsm_grid), intent(in) :: g
    dpsm_associated = c_associated(g%ptr)
  end function dpsm_associated

  ! ==== creating and destroying ==============================================

  !> Stores a newly created handle (or none) in g.
  subroutine adopt(g, ptr, status)
    type(dpsm_grid), intent(out) :: g
    type(c_ptr), intent(in) :: ptr
    integer(c_int), intent(in) :: status
    if (status == DPSM_OK) then
      g%ptr = ptr
      allocate (g%state)
    end if
  end subroutine adopt

  !> Makes the library's messages on a new grid count cells and array
  !> positions from 1, as the Fortran host does. A mesh keeps the start index
  !> it was made with (a restart file of a C host's mesh counts from 0); the
  !> call with 0 then succeeds and leaves no message behind.
  subroutine count_from_one(ptr, status)
    type(c_ptr), intent(in) :: ptr
    integer(c_int), intent(in) :: status
    integer(c_int) :: ignored
    if (status /= DPSM_OK) return
    if (c_dpsm_set_index_base(ptr, 1_c_int) /= DPSM_OK) ignored = c_dpsm_set_index_base(ptr, 0_c_int)
  end subroutine count_from_one

  !> dpsm_adopt_handle(g, ptr, status): g takes the handle ptr that a C
  !> constructor returned with status (none unless status is DPSM_OK); the
  !> library's messages on it count from 1, as on the module's own grids.
  subroutine dpsm_adopt_handle(g, ptr, status)
    type(dpsm_grid), intent(out) :: g
    type(c_ptr), intent(in) :: ptr
    integer(c_int), intent(in) :: status
    call count_from_one(ptr, status)
    call adopt(g, ptr, status)
  end subroutine dpsm_adopt_handle

  !> dpsm_create_1d(g, nx, dx[, ierr]): a 1D grid of nx cells of width dx.
  subroutine create_1d_i64(g, nx, dx, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int64_t), intent(in) :: nx
    real(c_double), intent(in) :: dx
    integer, intent(out), optional :: ierr
    type(c_ptr) :: ptr
    integer(c_int) :: status
    status = c_dpsm_create_1d(nx, dx, ptr)
    call count_from_one(ptr, status)
    call adopt(g, ptr, status)
    call finish(status, ierr, 'dpsm_create_1d')
  end subroutine create_1d_i64

  subroutine create_1d_i32(g, nx, dx, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int32_t), intent(in) :: nx
    real(c_double), intent(in) :: dx
    integer, intent(out), optional :: ierr
    call create_1d_i64(g, i64(nx), dx, ierr)
  end subroutine create_1d_i32

  !> dpsm_create_2d(g, nx, ny, dx, dy[, ierr]): a 2D grid of nx by ny cells.
  subroutine create_2d_i64(g, nx, ny, dx, dy, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int64_t), intent(in) :: nx, ny
    real(c_double), intent(in) :: dx, dy
    integer, intent(out), optional :: ierr
    type(c_ptr) :: ptr
    integer(c_int) :: status
    status = c_dpsm_create_2d(nx, ny, dx, dy, ptr)
    call count_from_one(ptr, status)
    call adopt(g, ptr, status)
    call finish(status, ierr, 'dpsm_create_2d')
  end subroutine create_2d_i64

  subroutine create_2d_i32(g, nx, ny, dx, dy, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int32_t), intent(in) :: nx, ny
    real(c_double), intent(in) :: dx, dy
    integer, intent(out), optional :: ierr
    call create_2d_i64(g, i64(nx), i64(ny), dx, dy, ierr)
  end subroutine create_2d_i32

  !> dpsm_create_axisymmetric(g, nr, dr[, ierr]): nr rings of width dr.
  subroutine create_axisymmetric_i64(g, nr, dr, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int64_t), intent(in) :: nr
    real(c_double), intent(in) :: dr
    integer, intent(out), optional :: ierr
    type(c_ptr) :: ptr
    integer(c_int) :: status
    status = c_dpsm_create_axisymmetric(nr, dr, ptr)
    call count_from_one(ptr, status)
    call adopt(g, ptr, status)
    call finish(status, ierr, 'dpsm_create_axisymmetric')
  end subroutine create_axisymmetric_i64

  subroutine create_axisymmetric_i32(g, nr, dr, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int32_t), intent(in) :: nr
    real(c_double), intent(in) :: dr
    integer, intent(out), optional :: ierr
    call create_axisymmetric_i64(g, i64(nr), dr, ierr)
  end subroutine create_axisymmetric_i32

  !> dpsm_destroy(g[, ierr]): releases the grid and leaves g empty. An empty g
  !> is allowed and does nothing; ierr is always DPSM_OK.
  subroutine dpsm_destroy(g, ierr)
    type(dpsm_grid), intent(inout) :: g
    integer, intent(out), optional :: ierr
    call c_dpsm_destroy(g%ptr)
    g%ptr = c_null_ptr
    if (associated(g%state)) then
      call clear_message(g)
      deallocate (g%state)
    end if
    if (present(ierr)) ierr = int(DPSM_OK)
  end subroutine dpsm_destroy

  ! ==== meshes ===============================================================
  !
  ! The constructors take the host's arrays with 1-based node and cell
  ! indices, as Fortran hosts hold them, and hand them to C as they are with
  ! start_index 1 (C's dpsm_create_mesh_indexed and the others):
  ! cell_start(ncells+1) starts at 1 (cell c has the nodes
  ! cell_nodes(cell_start(c) : cell_start(c+1)-1)), face_cells(2, nfaces) holds
  ! 0 for the domain edge, triangle_nodes(3, ntriangles). Coordinates are
  ! node_xy(2, nnodes) (x in row 1, y in row 2: C's (x, y) pairs).
  ! dpsm_create_mesh_indexed(g, start_index, ...) and the other two take the
  ! start index as their second argument: 0 for arrays counting from 0 (a
  ! UGRID file's start_index = 0: cell_start(1) = 0, -1 for the domain edge),
  ! 1 as the routines without it.
  !
  ! The sizes are checked against the arrays here (a mismatch fails with
  ! DPSM_ERR_INVALID_SIZE and a message naming both, which dpsm_last_error()
  ! returns); everything else is checked by C, whose messages count as the
  ! host does: cell, node, face and triangle numbers from the start index, the
  ! values as the host gave them, array positions as Fortran writes them from
  ! 1 (a node index 10 on a mesh of 9 nodes in cell_nodes(3) reads
  ! "cell_nodes(3) = 10 is not a node index in [1, 9]"; a face_cells(2, 5) of
  ! -3 on 2 cells reads "face 5: face_cells(2, 5) = -3 is not a cell index in
  ! [1, 2] nor 0 (the domain edge)"). They name the C function called,
  ! dpsm_create_mesh_indexed for dpsm_create_mesh. The mesh keeps its start
  ! index: later messages count from it too (dpsm_set_heights' "h(3) (cell
  ! 3)", dpsm_set_edge_kinds' "kinds(12) (face 12, on the domain edge)", in a
  ! restart file's mesh as well), and dpsm_get_mesh_faces returns its cells
  ! from it. The routines that take or return face arrays number the faces
  ! from 1, as the other arrays.

  !> Records a failure found on the Fortran side when there is no grid to
  !> keep it, for dpsm_last_error().
  subroutine set_no_grid_message(message)
    character(len=*), intent(in) :: message
    no_grid_message = message
    no_grid_snapshot = from_c_string(c_dpsm_last_error(c_null_ptr))
  end subroutine set_no_grid_message

  !> dpsm_last_error(NULL): C's message, or a newer one of the Fortran side.
  function last_error_without_grid() result(message)
    character(len=:), allocatable :: message
    message = from_c_string(c_dpsm_last_error(c_null_ptr))
    if (allocated(no_grid_message) .and. allocated(no_grid_snapshot)) then
      if (len(message) == len(no_grid_snapshot)) then
        if (message == no_grid_snapshot) message = no_grid_message
      end if
    end if
  end function last_error_without_grid

  !> DPSM_OK when `array_shape` is (rows, n), else DPSM_ERR_INVALID_SIZE with
  !> a message without a grid.
  function check_columns(where, name, array_shape, rows, n, n_name) result(status)
    character(len=*), intent(in) :: where, name, n_name
    integer, intent(in) :: array_shape(:)
    integer, intent(in) :: rows
    integer(c_int64_t), intent(in) :: n
    integer(c_int) :: status
    status = DPSM_OK
    if (size(array_shape) == 2) then
      if (array_shape(1) == rows .and. int(array_shape(2), c_int64_t) == n) return
    else
      if (int(array_shape(1), c_int64_t) == n) return
    end if
    status = DPSM_ERR_INVALID_SIZE
    if (size(array_shape) == 2) then
      call set_no_grid_message(where//': '//name//' has shape '//shape_string(array_shape)//' but '//n_name//' = '// &
                               itoa(n)//': pass '//name//'('//itoa(int(rows, c_int64_t))//', '//n_name//')')
    else
      call set_no_grid_message(where//': '//name//' has '//itoa(int(array_shape(1), c_int64_t))//' values but '// &
                               n_name//' = '//itoa(n)//': pass '//name//'('//n_name//')')
    end if
  end function check_columns

  !> dpsm_create_mesh(g, nnodes, node_xy, ncells, cell_start, cell_nodes[, ierr]):
  !> a mesh of polygonal cells, node_xy(2, nnodes), cell_start(ncells+1) from 1,
  !> cell_nodes(cell_start(ncells+1)-1) of 1-based node indices. Sizes and
  !> indices are integer(c_int64_t) or all default integers.
  subroutine create_mesh_i64(g, nnodes, node_xy, ncells, cell_start, cell_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int64_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int64_t), intent(in) :: ncells
    integer(c_int64_t), intent(in), contiguous :: cell_start(:), cell_nodes(:)
    integer, intent(out), optional :: ierr
    call make_mesh(g, 'dpsm_create_mesh', 1, nnodes, node_xy, ncells, cell_start, cell_nodes, ierr)
  end subroutine create_mesh_i64

  subroutine create_mesh_i32(g, nnodes, node_xy, ncells, cell_start, cell_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int32_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int32_t), intent(in) :: ncells
    integer(c_int32_t), intent(in) :: cell_start(:), cell_nodes(:)
    integer, intent(out), optional :: ierr
    call create_mesh_i64(g, i64(nnodes), node_xy, i64(ncells), i64(cell_start), i64(cell_nodes), ierr)
  end subroutine create_mesh_i32

  !> dpsm_create_mesh_indexed(g, start_index, nnodes, node_xy, ncells, cell_start, cell_nodes[, ierr]):
  !> as dpsm_create_mesh, the indices counting from start_index (0 or 1):
  !> cell_start(1) = start_index, node indices from start_index.
  subroutine create_mesh_indexed_i64(g, start_index, nnodes, node_xy, ncells, cell_start, cell_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int64_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int64_t), intent(in) :: ncells
    integer(c_int64_t), intent(in), contiguous :: cell_start(:), cell_nodes(:)
    integer, intent(out), optional :: ierr
    call make_mesh(g, 'dpsm_create_mesh_indexed', start_index, nnodes, node_xy, ncells, cell_start, cell_nodes, ierr)
  end subroutine create_mesh_indexed_i64

  subroutine create_mesh_indexed_i32(g, start_index, nnodes, node_xy, ncells, cell_start, cell_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int32_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int32_t), intent(in) :: ncells
    integer(c_int32_t), intent(in) :: cell_start(:), cell_nodes(:)
    integer, intent(out), optional :: ierr
    call create_mesh_indexed_i64(g, start_index, i64(nnodes), node_xy, i64(ncells), i64(cell_start), &
                                 i64(cell_nodes), ierr)
  end subroutine create_mesh_indexed_i32

  !> The polygons' constructor behind dpsm_create_mesh(_indexed): the shapes
  !> checked, then C's dpsm_create_mesh_indexed on the host's arrays.
  subroutine make_mesh(g, fn, start_index, nnodes, node_xy, ncells, cell_start, cell_nodes, ierr, geographic)
    type(dpsm_grid), intent(out) :: g
    character(len=*), intent(in) :: fn
    integer, intent(in) :: start_index
    integer(c_int64_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int64_t), intent(in) :: ncells
    integer(c_int64_t), intent(in), contiguous :: cell_start(:), cell_nodes(:)
    integer, intent(out), optional :: ierr
    logical, intent(in), optional :: geographic ! node_xy holds longitude and latitude: dpsm_create_mesh_geographic
    type(c_ptr) :: ptr
    integer(c_int) :: status
    character(len=:), allocatable :: count_name, xy_name
    logical :: lonlat
    lonlat = .false.
    if (present(geographic)) lonlat = geographic
    xy_name = 'node_xy'
    if (lonlat) xy_name = 'node_lonlat'
    status = DPSM_OK
    ! Counts below 1 and a start index other than 0 and 1 are refused by C,
    ! with its message, before it reads an array.
    if (nnodes >= 1 .and. ncells >= 1 .and. (start_index == 0 .or. start_index == 1)) then
      status = check_columns(fn, xy_name, shape(node_xy), 2, nnodes, 'nnodes')
      if (status == DPSM_OK) status = check_columns(fn, 'cell_start', shape(cell_start), 1, ncells + 1, 'ncells+1')
      ! C reads cell_start(ncells+1)-start_index node indices once
      ! cell_start(1) is start_index and every cell has at least 3 nodes; it
      ! refuses the others first.
      count_name = 'cell_start(ncells+1)'
      if (start_index == 1) count_name = count_name//'-1'
      if (status == DPSM_OK .and. cell_start(1) == start_index) &
        status = check_columns(fn, 'cell_nodes', shape(cell_nodes), 1, cell_start(ncells + 1) - start_index, &
                               count_name)
    end if
    ptr = c_null_ptr
    if (status == DPSM_OK .and. lonlat) then
      status = c_dpsm_create_mesh_geographic(int(start_index, c_int), nnodes, node_xy, ncells, cell_start, cell_nodes, &
                                             ptr)
    else if (status == DPSM_OK) then
      status = c_dpsm_create_mesh_indexed(int(start_index, c_int), nnodes, node_xy, ncells, cell_start, cell_nodes, ptr)
    end if
    call adopt(g, ptr, status)
    call finish(status, ierr, fn)
  end subroutine make_mesh

  !> dpsm_create_graph(g, ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length[, ierr]):
  !> a mesh from a finite-volume graph: cell_xy(2, ncells) centres,
  !> cell_area(ncells), face_cells(2, nfaces) the 1-based cells (a, b) of each
  !> face, b = 0 on the domain edge, face_xy(2, nfaces) midpoints,
  !> face_length(nfaces). Faces keep the host's order.
  subroutine create_graph_i64(g, ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int64_t), intent(in) :: ncells
    real(c_double), intent(in), contiguous :: cell_xy(:, :), cell_area(:)
    integer(c_int64_t), intent(in) :: nfaces
    integer(c_int64_t), intent(in), contiguous :: face_cells(:, :)
    real(c_double), intent(in), contiguous :: face_xy(:, :), face_length(:)
    integer, intent(out), optional :: ierr
    call make_graph(g, 'dpsm_create_graph', 1, ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, &
                    ierr)
  end subroutine create_graph_i64

  subroutine create_graph_i32(g, ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int32_t), intent(in) :: ncells
    real(c_double), intent(in), contiguous :: cell_xy(:, :), cell_area(:)
    integer(c_int32_t), intent(in) :: nfaces
    integer(c_int32_t), intent(in), contiguous :: face_cells(:, :)
    real(c_double), intent(in), contiguous :: face_xy(:, :), face_length(:)
    integer, intent(out), optional :: ierr
    call create_graph_i64(g, i64(ncells), cell_xy, cell_area, i64(nfaces), i64(face_cells), face_xy, face_length, ierr)
  end subroutine create_graph_i32

  !> dpsm_create_graph_indexed(g, start_index, ncells, cell_xy, cell_area, nfaces, face_cells, face_xy,
  !> face_length[, ierr]): as dpsm_create_graph, the cells in face_cells
  !> counting from start_index (0 or 1), start_index-1 on the domain edge.
  subroutine create_graph_indexed_i64(g, start_index, ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, &
                                      face_length, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int64_t), intent(in) :: ncells
    real(c_double), intent(in), contiguous :: cell_xy(:, :), cell_area(:)
    integer(c_int64_t), intent(in) :: nfaces
    integer(c_int64_t), intent(in), contiguous :: face_cells(:, :)
    real(c_double), intent(in), contiguous :: face_xy(:, :), face_length(:)
    integer, intent(out), optional :: ierr
    call make_graph(g, 'dpsm_create_graph_indexed', start_index, ncells, cell_xy, cell_area, nfaces, face_cells, &
                    face_xy, face_length, ierr)
  end subroutine create_graph_indexed_i64

  subroutine create_graph_indexed_i32(g, start_index, ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, &
                                      face_length, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int32_t), intent(in) :: ncells
    real(c_double), intent(in), contiguous :: cell_xy(:, :), cell_area(:)
    integer(c_int32_t), intent(in) :: nfaces
    integer(c_int32_t), intent(in), contiguous :: face_cells(:, :)
    real(c_double), intent(in), contiguous :: face_xy(:, :), face_length(:)
    integer, intent(out), optional :: ierr
    call create_graph_indexed_i64(g, start_index, i64(ncells), cell_xy, cell_area, i64(nfaces), i64(face_cells), &
                                  face_xy, face_length, ierr)
  end subroutine create_graph_indexed_i32

  !> The graph's constructor behind dpsm_create_graph(_indexed): the shapes
  !> checked, then C's dpsm_create_graph_indexed on the host's arrays.
  subroutine make_graph(g, fn, start_index, ncells, cell_xy, cell_area, nfaces, face_cells, face_xy, face_length, ierr)
    type(dpsm_grid), intent(out) :: g
    character(len=*), intent(in) :: fn
    integer, intent(in) :: start_index
    integer(c_int64_t), intent(in) :: ncells
    real(c_double), intent(in), contiguous :: cell_xy(:, :), cell_area(:)
    integer(c_int64_t), intent(in) :: nfaces
    integer(c_int64_t), intent(in), contiguous :: face_cells(:, :)
    real(c_double), intent(in), contiguous :: face_xy(:, :), face_length(:)
    integer, intent(out), optional :: ierr
    type(c_ptr) :: ptr
    integer(c_int) :: status
    status = DPSM_OK
    if (ncells >= 1 .and. nfaces >= 1) then
      status = check_columns(fn, 'cell_xy', shape(cell_xy), 2, ncells, 'ncells')
      if (status == DPSM_OK) status = check_columns(fn, 'cell_area', shape(cell_area), 1, ncells, 'ncells')
      if (status == DPSM_OK) status = check_columns(fn, 'face_cells', shape(face_cells), 2, nfaces, 'nfaces')
      if (status == DPSM_OK) status = check_columns(fn, 'face_xy', shape(face_xy), 2, nfaces, 'nfaces')
      if (status == DPSM_OK) status = check_columns(fn, 'face_length', shape(face_length), 1, nfaces, 'nfaces')
    end if
    ptr = c_null_ptr
    if (status == DPSM_OK) &
      status = c_dpsm_create_graph_indexed(int(start_index, c_int), ncells, cell_xy, cell_area, nfaces, face_cells, &
                                           face_xy, face_length, ptr)
    call adopt(g, ptr, status)
    call finish(status, ierr, fn)
  end subroutine make_graph

  !> dpsm_create_dual_mesh(g, nnodes, node_xy, ntriangles, triangle_nodes[, ierr]):
  !> the median dual of a triangle mesh, one cell per node: node_xy(2, nnodes),
  !> triangle_nodes(3, ntriangles) of 1-based node indices.
  subroutine create_dual_mesh_i64(g, nnodes, node_xy, ntriangles, triangle_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int64_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int64_t), intent(in) :: ntriangles
    integer(c_int64_t), intent(in), contiguous :: triangle_nodes(:, :)
    integer, intent(out), optional :: ierr
    call make_dual_mesh(g, 'dpsm_create_dual_mesh', 1, nnodes, node_xy, ntriangles, triangle_nodes, ierr)
  end subroutine create_dual_mesh_i64

  subroutine create_dual_mesh_i32(g, nnodes, node_xy, ntriangles, triangle_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer(c_int32_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int32_t), intent(in) :: ntriangles
    integer(c_int32_t), intent(in), contiguous :: triangle_nodes(:, :)
    integer, intent(out), optional :: ierr
    call create_dual_mesh_i64(g, i64(nnodes), node_xy, i64(ntriangles), i64(triangle_nodes), ierr)
  end subroutine create_dual_mesh_i32

  !> dpsm_create_dual_mesh_indexed(g, start_index, nnodes, node_xy, ntriangles, triangle_nodes[, ierr]):
  !> as dpsm_create_dual_mesh, the node indices counting from start_index (0 or 1).
  subroutine create_dual_mesh_indexed_i64(g, start_index, nnodes, node_xy, ntriangles, triangle_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int64_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int64_t), intent(in) :: ntriangles
    integer(c_int64_t), intent(in), contiguous :: triangle_nodes(:, :)
    integer, intent(out), optional :: ierr
    call make_dual_mesh(g, 'dpsm_create_dual_mesh_indexed', start_index, nnodes, node_xy, ntriangles, triangle_nodes, &
                        ierr)
  end subroutine create_dual_mesh_indexed_i64

  subroutine create_dual_mesh_indexed_i32(g, start_index, nnodes, node_xy, ntriangles, triangle_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int32_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int32_t), intent(in) :: ntriangles
    integer(c_int32_t), intent(in), contiguous :: triangle_nodes(:, :)
    integer, intent(out), optional :: ierr
    call create_dual_mesh_indexed_i64(g, start_index, i64(nnodes), node_xy, i64(ntriangles), i64(triangle_nodes), ierr)
  end subroutine create_dual_mesh_indexed_i32

  !> The dual's constructor behind dpsm_create_dual_mesh(_indexed): the
  !> shapes checked, then C's dpsm_create_dual_mesh_indexed on the host's arrays.
  subroutine make_dual_mesh(g, fn, start_index, nnodes, node_xy, ntriangles, triangle_nodes, ierr, geographic)
    type(dpsm_grid), intent(out) :: g
    character(len=*), intent(in) :: fn
    integer, intent(in) :: start_index
    integer(c_int64_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int64_t), intent(in) :: ntriangles
    integer(c_int64_t), intent(in), contiguous :: triangle_nodes(:, :)
    integer, intent(out), optional :: ierr
    logical, intent(in), optional :: geographic ! node_xy holds longitude and latitude
    type(c_ptr) :: ptr
    integer(c_int) :: status
    logical :: lonlat
    lonlat = .false.
    if (present(geographic)) lonlat = geographic
    status = DPSM_OK
    if (nnodes >= 1 .and. ntriangles >= 1) then
      if (lonlat) then
        status = check_columns(fn, 'node_lonlat', shape(node_xy), 2, nnodes, 'nnodes')
      else
        status = check_columns(fn, 'node_xy', shape(node_xy), 2, nnodes, 'nnodes')
      end if
      if (status == DPSM_OK) &
        status = check_columns(fn, 'triangle_nodes', shape(triangle_nodes), 3, ntriangles, 'ntriangles')
    end if
    ptr = c_null_ptr
    if (status == DPSM_OK .and. lonlat) then
      status = c_dpsm_create_dual_mesh_geographic(int(start_index, c_int), nnodes, node_xy, ntriangles, &
                                                  triangle_nodes, ptr)
    else if (status == DPSM_OK) then
      status = c_dpsm_create_dual_mesh_indexed(int(start_index, c_int), nnodes, node_xy, ntriangles, triangle_nodes, ptr)
    end if
    call adopt(g, ptr, status)
    call finish(status, ierr, fn)
  end subroutine make_dual_mesh

  !> dpsm_create_mesh_geographic(g, start_index, nnodes, node_lonlat, ncells, cell_start, cell_nodes[, ierr]):
  !> as dpsm_create_mesh_indexed, node_lonlat(2, nnodes) the longitude and
  !> latitude of each node in degrees: lengths and areas on the sphere.
  subroutine create_mesh_geographic_i64(g, start_index, nnodes, node_lonlat, ncells, cell_start, cell_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int64_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_lonlat(:, :)
    integer(c_int64_t), intent(in) :: ncells
    integer(c_int64_t), intent(in), contiguous :: cell_start(:), cell_nodes(:)
    integer, intent(out), optional :: ierr
    call make_mesh(g, 'dpsm_create_mesh_geographic', start_index, nnodes, node_lonlat, ncells, cell_start, cell_nodes, &
                   ierr, geographic=.true.)
  end subroutine create_mesh_geographic_i64

  subroutine create_mesh_geographic_i32(g, start_index, nnodes, node_lonlat, ncells, cell_start, cell_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int32_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_lonlat(:, :)
    integer(c_int32_t), intent(in) :: ncells
    integer(c_int32_t), intent(in) :: cell_start(:), cell_nodes(:)
    integer, intent(out), optional :: ierr
    call create_mesh_geographic_i64(g, start_index, i64(nnodes), node_lonlat, i64(ncells), i64(cell_start), &
                                    i64(cell_nodes), ierr)
  end subroutine create_mesh_geographic_i32

  !> dpsm_create_dual_mesh_geographic(g, start_index, nnodes, node_lonlat, ntriangles, triangle_nodes[, ierr]):
  !> as dpsm_create_dual_mesh_indexed, node_lonlat(2, nnodes) in degrees.
  subroutine create_dual_mesh_geographic_i64(g, start_index, nnodes, node_lonlat, ntriangles, triangle_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int64_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_lonlat(:, :)
    integer(c_int64_t), intent(in) :: ntriangles
    integer(c_int64_t), intent(in), contiguous :: triangle_nodes(:, :)
    integer, intent(out), optional :: ierr
    call make_dual_mesh(g, 'dpsm_create_dual_mesh_geographic', start_index, nnodes, node_lonlat, ntriangles, &
                        triangle_nodes, ierr, geographic=.true.)
  end subroutine create_dual_mesh_geographic_i64

  subroutine create_dual_mesh_geographic_i32(g, start_index, nnodes, node_lonlat, ntriangles, triangle_nodes, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: start_index
    integer(c_int32_t), intent(in) :: nnodes
    real(c_double), intent(in), contiguous :: node_lonlat(:, :)
    integer(c_int32_t), intent(in) :: ntriangles
    integer(c_int32_t), intent(in), contiguous :: triangle_nodes(:, :)
    integer, intent(out), optional :: ierr
    call create_dual_mesh_geographic_i64(g, start_index, i64(nnodes), node_lonlat, i64(ntriangles), &
                                         i64(triangle_nodes), ierr)
  end subroutine create_dual_mesh_geographic_i32

  !> dpsm_get_cell_centres(g[, cell_xy][, cell_area][, ierr]): where each
  !> cell's height stands, cell_xy(2, ncells) (longitude and latitude in
  !> degrees on a geographic mesh), and the area that turns it into a volume,
  !> cell_area(ncells), ncells = nx*ny of dpsm_get_shape (x fastest on a grid);
  !> either may be left out (pass them by keyword), not both.
  subroutine dpsm_get_cell_centres(g, cell_xy, cell_area, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(inout), contiguous, optional :: cell_xy(:, :)
    real(c_double), intent(inout), contiguous, optional :: cell_area(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    integer(c_int64_t) :: nx, ny
    call clear_message(g)
    status = c_dpsm_get_shape(g%ptr, nx, ny)
    if (status == DPSM_OK .and. present(cell_xy)) then
      if (size(cell_xy, 1) /= 2 .or. int(size(cell_xy, 2), c_int64_t) /= nx*ny) then
        status = DPSM_ERR_INVALID_SIZE
        call set_message(g, 'dpsm_get_cell_centres: cell_xy has shape '//shape_string(shape(cell_xy))// &
                         ' but the grid has '//itoa(nx*ny)//' cells: pass cell_xy(2, '//itoa(nx*ny)//')')
      end if
    end if
    if (status == DPSM_OK .and. present(cell_area)) then
      if (int(size(cell_area), c_int64_t) /= nx*ny) then
        status = DPSM_ERR_INVALID_SIZE
        call set_message(g, 'dpsm_get_cell_centres: cell_area has '//itoa(int(size(cell_area), c_int64_t))// &
                         ' values but the grid has '//itoa(nx*ny)//' cells: pass cell_area('//itoa(nx*ny)//')')
      end if
    end if
    ! An absent assumed-shape array has no descriptor to take the address of:
    ! each case is its own call (absent arguments reach C as NULL).
    if (status == DPSM_OK) then
      if (present(cell_xy) .and. present(cell_area)) then
        status = c_dpsm_get_cell_centres(g%ptr, cell_xy, cell_area)
      else if (present(cell_xy)) then
        status = c_dpsm_get_cell_centres(g%ptr, cell_xy=cell_xy)
      else if (present(cell_area)) then
        status = c_dpsm_get_cell_centres(g%ptr, cell_area=cell_area)
      else
        status = c_dpsm_get_cell_centres(g%ptr)
      end if
    end if
    call finish(status, ierr, 'dpsm_get_cell_centres', g)
  end subroutine dpsm_get_cell_centres

  !> dpsm_get_face_count(g, nfaces[, ierr]): the faces of a mesh, interior and
  !> on the domain edge (DPSM_ERR_NOT_APPLICABLE on a grid).
  subroutine get_face_count_i64(g, nfaces, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(out) :: nfaces
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_get_face_count(g%ptr, nfaces), ierr, 'dpsm_get_face_count', g)
  end subroutine get_face_count_i64

  subroutine get_face_count_i32(g, nfaces, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(out) :: nfaces
    integer, intent(out), optional :: ierr
    integer(c_int64_t) :: n64
    integer(c_int) :: status
    call clear_message(g)
    nfaces = 0
    status = c_dpsm_get_face_count(g%ptr, n64)
    if (status == DPSM_OK) then
      if (n64 > huge(nfaces)) then
        status = DPSM_ERR_INVALID_SIZE
        call set_message(g, 'dpsm_get_face_count: the mesh has nfaces = '//itoa(n64)// &
                         ', too large for integer(c_int32_t): pass an integer(c_int64_t) variable')
      else
        nfaces = int(n64, c_int32_t)
      end if
    end if
    call finish(status, ierr, 'dpsm_get_face_count', g)
  end subroutine get_face_count_i32

  !> The mesh's face count into nfaces (DPSM_OK), or the status of C's refusal
  !> (DPSM_ERR_NOT_APPLICABLE on a grid, DPSM_ERR_NULL_POINTER without one).
  function face_count(g, nfaces) result(status)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(out) :: nfaces
    integer(c_int) :: status
    nfaces = 0
    status = c_dpsm_get_face_count(g%ptr, nfaces)
  end function face_count

  !> As check_grid_shape, for an array of one value per face of a mesh:
  !> a(nfaces) or a(nfaces, 1).
  function check_face_shape(g, where, name, nfaces, array_shape) result(status)
    type(dpsm_grid), intent(in) :: g
    character(len=*), intent(in) :: where, name
    integer(c_int64_t), intent(in) :: nfaces
    integer, intent(in) :: array_shape(:)
    integer(c_int) :: status
    logical :: ok
    status = DPSM_OK
    if (size(array_shape) == 1) then
      ok = int(array_shape(1), c_int64_t) == nfaces
    else
      ok = int(array_shape(1), c_int64_t) == nfaces .and. array_shape(2) == 1
    end if
    if (ok) return
    status = DPSM_ERR_INVALID_SIZE
    call set_message(g, where//': '//name//' has shape '//shape_string(array_shape)//' but the mesh has nfaces = '// &
                     itoa(nfaces)//': pass '//name//'(nfaces)')
  end function check_face_shape

  !> dpsm_get_mesh_faces(g, face_cells[, ierr]): face_cells(2, nfaces), the
  !> two cells (a, b) of every face as the mesh counts them: 1-based with
  !> b = 0 on the domain edge for a mesh of dpsm_create_mesh and the others
  !> (from the start index, one less on the edge, for one of the _indexed
  !> routines), in the host's face order (that of dpsm_get_face_fluxes,
  !> dpsm_set_edge_kinds and the levels of DPSM_MESH_EDGE).
  !> integer(c_int64_t) or default integers.
  subroutine get_mesh_faces_i64(g, face_cells, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(inout), contiguous :: face_cells(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int64_t), allocatable :: cells(:)
    integer(c_int) :: status
    call clear_message(g)
    status = mesh_faces(g, shape(face_cells), cells)
    if (status == DPSM_OK) face_cells = reshape(cells, shape(face_cells))
    call finish(status, ierr, 'dpsm_get_mesh_faces', g)
  end subroutine get_mesh_faces_i64

  subroutine get_mesh_faces_i32(g, face_cells, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(inout), contiguous :: face_cells(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int64_t), allocatable :: cells(:)
    integer(c_int) :: status
    call clear_message(g)
    status = mesh_faces(g, shape(face_cells), cells)
    if (status == DPSM_OK) then
      if (maxval(cells) > huge(face_cells)) then
        status = DPSM_ERR_INVALID_SIZE
        call set_message(g, 'dpsm_get_mesh_faces: the mesh has cells beyond huge(integer(c_int32_t)): '// &
                         'pass an integer(c_int64_t) face_cells')
      else
        face_cells = reshape(int(cells, c_int32_t), shape(face_cells))
      end if
    end if
    call finish(status, ierr, 'dpsm_get_mesh_faces', g)
  end subroutine get_mesh_faces_i32

  !> The faces' cells as C gives them (from the mesh's start index), after
  !> the shape check.
  function mesh_faces(g, array_shape, cells) result(status)
    type(dpsm_grid), intent(in) :: g
    integer, intent(in) :: array_shape(:)
    integer(c_int64_t), allocatable, intent(out) :: cells(:)
    integer(c_int) :: status
    integer(c_int64_t) :: nfaces
    status = face_count(g, nfaces)
    if (status /= DPSM_OK) then
      ! C's message (a grid, not a mesh; no grid) comes with the call itself.
      allocate (cells(1))
      status = c_dpsm_get_mesh_faces(g%ptr, cells)
      return
    end if
    if (array_shape(1) /= 2 .or. int(array_shape(2), c_int64_t) /= nfaces) then
      status = DPSM_ERR_INVALID_SIZE
      call set_message(g, 'dpsm_get_mesh_faces: face_cells has shape '//shape_string(array_shape)// &
                       ' but the mesh has nfaces = '//itoa(nfaces)//': pass face_cells(2, nfaces)')
      return
    end if
    allocate (cells(2*nfaces))
    status = c_dpsm_get_mesh_faces(g%ptr, cells)
  end function mesh_faces

  !> dpsm_set_edge_kinds(g, kinds[, ierr]): kinds(nfaces) of DPSM_OPEN or
  !> DPSM_WALL as integer(c_int8_t) (int(DPSM_OPEN, c_int8_t)), one per face,
  !> those of interior faces ignored; without kinds every edge face is a wall.
  subroutine set_edge_kinds_r1(g, kinds, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int8_t), intent(in), contiguous :: kinds(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    integer(c_int64_t) :: nfaces
    call clear_message(g)
    status = face_count(g, nfaces)
    if (status == DPSM_OK) then
      status = check_face_shape(g, 'dpsm_set_edge_kinds', 'kinds', nfaces, shape(kinds))
      if (status == DPSM_OK) status = c_dpsm_set_edge_kinds(g%ptr, kinds)
    else
      status = c_dpsm_set_edge_kinds(g%ptr) ! refused by C (a grid; no grid), with its message
    end if
    call finish(status, ierr, 'dpsm_set_edge_kinds', g)
  end subroutine set_edge_kinds_r1

  subroutine set_edge_kinds_none(g, ierr)
    type(dpsm_grid), intent(in) :: g
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_edge_kinds(g%ptr), ierr, 'dpsm_set_edge_kinds', g)
  end subroutine set_edge_kinds_none

  ! ==== parameters ===========================================================

  !> dpsm_set_repose_angle(g, theta_radians[, ierr])
  subroutine dpsm_set_repose_angle(g, theta_radians, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in) :: theta_radians
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_repose_angle(g%ptr, theta_radians), ierr, 'dpsm_set_repose_angle', g)
  end subroutine dpsm_set_repose_angle

  !> dpsm_set_mobility(g, nu[, ierr])
  subroutine dpsm_set_mobility(g, nu, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in) :: nu
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_mobility(g%ptr, nu), ierr, 'dpsm_set_mobility', g)
  end subroutine dpsm_set_mobility

  !> dpsm_set_scheme(g, scheme[, ierr]): DPSM_SCHEME_ISOTROPIC or DPSM_SCHEME_PAIRWISE.
  subroutine dpsm_set_scheme(g, scheme, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: scheme
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_scheme(g%ptr, scheme), ierr, 'dpsm_set_scheme', g)
  end subroutine dpsm_set_scheme

  !> dpsm_set_relaxation(g, relaxation[, ierr]): DPSM_RELAX_AUTO (the default:
  !> sub-steps over dt, as DPSM_RELAX_TIME_ACCURATE),
  !> DPSM_RELAX_TO_REST (each dpsm_step relaxes to rest, fast),
  !> DPSM_RELAX_TIME_ACCURATE (sub-steps over dt) or DPSM_RELAX_LOCAL_STEPS
  !> (sub-steps over dt, each mesh cell at its own pace).
  subroutine dpsm_set_relaxation(g, relaxation, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: relaxation
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_relaxation(g%ptr, relaxation), ierr, 'dpsm_set_relaxation', g)
  end subroutine dpsm_set_relaxation

  !> dpsm_set_boundary(g, side, kind[, ierr]): side DPSM_XMIN..DPSM_YMAX, kind DPSM_OPEN or DPSM_WALL.
  subroutine dpsm_set_boundary(g, side, kind, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: side, kind
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_boundary(g%ptr, side, kind), ierr, 'dpsm_set_boundary', g)
  end subroutine dpsm_set_boundary

  !> dpsm_set_rest_tolerance(g, tol[, ierr])
  subroutine dpsm_set_rest_tolerance(g, tol, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in) :: tol
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_rest_tolerance(g%ptr, tol), ierr, 'dpsm_set_rest_tolerance', g)
  end subroutine dpsm_set_rest_tolerance

  !> dpsm_set_max_substeps(g, n[, ierr])
  subroutine set_max_substeps_i64(g, n, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(in) :: n
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_max_substeps(g%ptr, n), ierr, 'dpsm_set_max_substeps', g)
  end subroutine set_max_substeps_i64

  subroutine set_max_substeps_i32(g, n, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(in) :: n
    integer, intent(out), optional :: ierr
    call set_max_substeps_i64(g, i64(n), ierr)
  end subroutine set_max_substeps_i32

  !> dpsm_set_index_base(g, base[, ierr]): 0 or 1, where the library's
  !> messages on g count cells and array positions from. The grids this module
  !> creates or loads count from 1 already; 0 gives C's messages.
  subroutine dpsm_set_index_base(g, base, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: base
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_index_base(g%ptr, base), ierr, 'dpsm_set_index_base', g)
  end subroutine dpsm_set_index_base

  !> dpsm_set_threads(g, n[, ierr]): 0 means OpenMP's default.
  subroutine dpsm_set_threads(g, n, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: n
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_threads(g%ptr, n), ierr, 'dpsm_set_threads', g)
  end subroutine dpsm_set_threads

  !> dpsm_get_threads(g, n[, ierr]): the threads dpsm_step will use (1 on a
  !> block of a distributed grid unless OMP_NUM_THREADS is set).
  subroutine dpsm_get_threads(g, n, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(out) :: n
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_get_threads(g%ptr, n), ierr, 'dpsm_get_threads', g)
  end subroutine dpsm_get_threads

  !> dpsm_get_grid_kind(g, kind[, ierr]): DPSM_GRID_1D, DPSM_GRID_AXISYMMETRIC,
  !> DPSM_GRID_2D or DPSM_GRID_MESH, the constructor that made g (through
  !> dpsm_load, the one that made the grid saved).
  subroutine dpsm_get_grid_kind(g, kind, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(out) :: kind
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_get_grid_kind(g%ptr, kind), ierr, 'dpsm_get_grid_kind', g)
  end subroutine dpsm_get_grid_kind

  ! ==== cell kinds ===========================================================

  !> dpsm_set_cell_kinds(g, kinds[, ierr]): kinds(nx, ny) or kinds(nx*ny) of
  !> DPSM_CELL_SAND, DPSM_CELL_WALL, DPSM_CELL_OPEN; without kinds every cell is sand.
  subroutine set_cell_kinds_r1(g, kinds, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int8_t), intent(in), contiguous :: kinds(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_cell_kinds', 'kinds', shape(kinds))
    if (status == DPSM_OK) status = c_dpsm_set_cell_kinds(g%ptr, kinds)
    call finish(status, ierr, 'dpsm_set_cell_kinds', g)
  end subroutine set_cell_kinds_r1

  subroutine set_cell_kinds_r2(g, kinds, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int8_t), intent(in), contiguous :: kinds(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_cell_kinds', 'kinds', shape(kinds))
    if (status == DPSM_OK) status = c_dpsm_set_cell_kinds(g%ptr, kinds)
    call finish(status, ierr, 'dpsm_set_cell_kinds', g)
  end subroutine set_cell_kinds_r2

  subroutine set_cell_kinds_none(g, ierr)
    type(dpsm_grid), intent(in) :: g
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_cell_kinds(g%ptr), ierr, 'dpsm_set_cell_kinds', g)
  end subroutine set_cell_kinds_none

  ! ==== heights ==============================================================

  !> dpsm_set_heights(g, h[, ierr]): h(nx, ny) or h(nx*ny).
  subroutine set_heights_r1(g, h, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in), contiguous :: h(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_heights', 'h', shape(h))
    if (status == DPSM_OK) status = c_dpsm_set_heights(g%ptr, h)
    call finish(status, ierr, 'dpsm_set_heights', g)
  end subroutine set_heights_r1

  subroutine set_heights_r2(g, h, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in), contiguous :: h(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_heights', 'h', shape(h))
    if (status == DPSM_OK) status = c_dpsm_set_heights(g%ptr, h)
    call finish(status, ierr, 'dpsm_set_heights', g)
  end subroutine set_heights_r2

  !> dpsm_get_heights(g, h[, ierr]): h(nx, ny) or h(nx*ny).
  subroutine get_heights_r1(g, h, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(inout), contiguous :: h(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_get_heights', 'h', shape(h))
    if (status == DPSM_OK) status = c_dpsm_get_heights(g%ptr, h)
    call finish(status, ierr, 'dpsm_get_heights', g)
  end subroutine get_heights_r1

  subroutine get_heights_r2(g, h, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(inout), contiguous :: h(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_get_heights', 'h', shape(h))
    if (status == DPSM_OK) status = c_dpsm_get_heights(g%ptr, h)
    call finish(status, ierr, 'dpsm_get_heights', g)
  end subroutine get_heights_r2

  ! ==== blocks of heights (i0, j0 are 0-based, as in C) ======================

  !> dpsm_set_heights_region(g, i0, j0, ni, nj, h[, ierr]): h(ni, nj) or h(ni*nj).
  subroutine set_heights_region_i64_r1(g, i0, j0, ni, nj, h, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(in), contiguous :: h(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_block_shape(g, 'dpsm_set_heights_region', 'h', ni, nj, shape(h))
    if (status == DPSM_OK) status = c_dpsm_set_heights_region(g%ptr, i0, j0, ni, nj, h)
    call finish(status, ierr, 'dpsm_set_heights_region', g)
  end subroutine set_heights_region_i64_r1

  subroutine set_heights_region_i64_r2(g, i0, j0, ni, nj, h, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(in), contiguous :: h(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_block_shape(g, 'dpsm_set_heights_region', 'h', ni, nj, shape(h))
    if (status == DPSM_OK) status = c_dpsm_set_heights_region(g%ptr, i0, j0, ni, nj, h)
    call finish(status, ierr, 'dpsm_set_heights_region', g)
  end subroutine set_heights_region_i64_r2

  subroutine set_heights_region_i32_r1(g, i0, j0, ni, nj, h, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(in), contiguous :: h(:)
    integer, intent(out), optional :: ierr
    call set_heights_region_i64_r1(g, i64(i0), i64(j0), i64(ni), i64(nj), h, ierr)
  end subroutine set_heights_region_i32_r1

  subroutine set_heights_region_i32_r2(g, i0, j0, ni, nj, h, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(in), contiguous :: h(:, :)
    integer, intent(out), optional :: ierr
    call set_heights_region_i64_r2(g, i64(i0), i64(j0), i64(ni), i64(nj), h, ierr)
  end subroutine set_heights_region_i32_r2

  !> dpsm_add_heights_region(g, i0, j0, ni, nj, dh[, ierr]): dh(ni, nj) or dh(ni*nj).
  subroutine add_heights_region_i64_r1(g, i0, j0, ni, nj, dh, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(in), contiguous :: dh(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_block_shape(g, 'dpsm_add_heights_region', 'dh', ni, nj, shape(dh))
    if (status == DPSM_OK) status = c_dpsm_add_heights_region(g%ptr, i0, j0, ni, nj, dh)
    call finish(status, ierr, 'dpsm_add_heights_region', g)
  end subroutine add_heights_region_i64_r1

  subroutine add_heights_region_i64_r2(g, i0, j0, ni, nj, dh, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(in), contiguous :: dh(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_block_shape(g, 'dpsm_add_heights_region', 'dh', ni, nj, shape(dh))
    if (status == DPSM_OK) status = c_dpsm_add_heights_region(g%ptr, i0, j0, ni, nj, dh)
    call finish(status, ierr, 'dpsm_add_heights_region', g)
  end subroutine add_heights_region_i64_r2

  subroutine add_heights_region_i32_r1(g, i0, j0, ni, nj, dh, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(in), contiguous :: dh(:)
    integer, intent(out), optional :: ierr
    call add_heights_region_i64_r1(g, i64(i0), i64(j0), i64(ni), i64(nj), dh, ierr)
  end subroutine add_heights_region_i32_r1

  subroutine add_heights_region_i32_r2(g, i0, j0, ni, nj, dh, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(in), contiguous :: dh(:, :)
    integer, intent(out), optional :: ierr
    call add_heights_region_i64_r2(g, i64(i0), i64(j0), i64(ni), i64(nj), dh, ierr)
  end subroutine add_heights_region_i32_r2

  !> dpsm_get_heights_region(g, i0, j0, ni, nj, h[, ierr]): h(ni, nj) or h(ni*nj).
  subroutine get_heights_region_i64_r1(g, i0, j0, ni, nj, h, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(inout), contiguous :: h(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_block_shape(g, 'dpsm_get_heights_region', 'h', ni, nj, shape(h))
    if (status == DPSM_OK) status = c_dpsm_get_heights_region(g%ptr, i0, j0, ni, nj, h)
    call finish(status, ierr, 'dpsm_get_heights_region', g)
  end subroutine get_heights_region_i64_r1

  subroutine get_heights_region_i64_r2(g, i0, j0, ni, nj, h, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(inout), contiguous :: h(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_block_shape(g, 'dpsm_get_heights_region', 'h', ni, nj, shape(h))
    if (status == DPSM_OK) status = c_dpsm_get_heights_region(g%ptr, i0, j0, ni, nj, h)
    call finish(status, ierr, 'dpsm_get_heights_region', g)
  end subroutine get_heights_region_i64_r2

  subroutine get_heights_region_i32_r1(g, i0, j0, ni, nj, h, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(inout), contiguous :: h(:)
    integer, intent(out), optional :: ierr
    call get_heights_region_i64_r1(g, i64(i0), i64(j0), i64(ni), i64(nj), h, ierr)
  end subroutine get_heights_region_i32_r1

  subroutine get_heights_region_i32_r2(g, i0, j0, ni, nj, h, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(in) :: i0, j0, ni, nj
    real(c_double), intent(inout), contiguous :: h(:, :)
    integer, intent(out), optional :: ierr
    call get_heights_region_i64_r2(g, i64(i0), i64(j0), i64(ni), i64(nj), h, ierr)
  end subroutine get_heights_region_i32_r2

  ! ==== sources ==============================================================

  !> dpsm_set_source(g, q[, ierr]): q(nx, ny) or q(nx*ny), height per unit
  !> time (deposition > 0, erosion < 0); without q no source acts.
  subroutine set_source_r1(g, q, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in), contiguous :: q(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_source', 'q', shape(q))
    if (status == DPSM_OK) status = c_dpsm_set_source(g%ptr, q)
    call finish(status, ierr, 'dpsm_set_source', g)
  end subroutine set_source_r1

  subroutine set_source_r2(g, q, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in), contiguous :: q(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_source', 'q', shape(q))
    if (status == DPSM_OK) status = c_dpsm_set_source(g%ptr, q)
    call finish(status, ierr, 'dpsm_set_source', g)
  end subroutine set_source_r2

  subroutine set_source_none(g, ierr)
    type(dpsm_grid), intent(in) :: g
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_source(g%ptr), ierr, 'dpsm_set_source', g)
  end subroutine set_source_none

  ! ==== stepping =============================================================

  !> dpsm_stable_dt(g, dt[, ierr]): the largest stable explicit sub-step.
  subroutine dpsm_stable_dt(g, dt, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(out) :: dt
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_stable_dt(g%ptr, dt), ierr, 'dpsm_stable_dt', g)
  end subroutine dpsm_stable_dt

  !> dpsm_step(g, dt[, ierr]): advances the surface by exactly dt.
  subroutine dpsm_step(g, dt, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in) :: dt
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_step(g%ptr, dt), ierr, 'dpsm_step', g)
  end subroutine dpsm_step

  ! ==== reading back =========================================================

  !> dpsm_get_mass(g, quantity, value[, ierr]): DPSM_MASS_TOTAL, _SOURCED, _EXTERNAL, _OUTFLOW or _UNMET.
  subroutine dpsm_get_mass(g, quantity, value, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: quantity
    real(c_double), intent(out) :: value
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_get_mass(g%ptr, quantity, value), ierr, 'dpsm_get_mass', g)
  end subroutine dpsm_get_mass

  !> dpsm_get_step_info(g, item, value[, ierr]): DPSM_INFO_* of the last step.
  subroutine dpsm_get_step_info(g, item, value, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: item
    real(c_double), intent(out) :: value
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_get_step_info(g%ptr, item, value), ierr, 'dpsm_get_step_info', g)
  end subroutine dpsm_get_step_info

  !> dpsm_get_shape(g, nx, ny[, ierr]): ny is 1 on 1D and axisymmetric grids.
  subroutine get_shape_i64(g, nx, ny, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int64_t), intent(out) :: nx, ny
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_get_shape(g%ptr, nx, ny), ierr, 'dpsm_get_shape', g)
  end subroutine get_shape_i64

  subroutine get_shape_i32(g, nx, ny, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int32_t), intent(out) :: nx, ny
    integer, intent(out), optional :: ierr
    integer(c_int64_t) :: nx64, ny64
    integer(c_int) :: status
    call clear_message(g)
    nx = 0
    ny = 0
    status = c_dpsm_get_shape(g%ptr, nx64, ny64)
    if (status == DPSM_OK) then
      if (nx64 > huge(nx) .or. ny64 > huge(ny)) then
        status = DPSM_ERR_INVALID_SIZE
        call set_message(g, 'dpsm_get_shape: the grid has nx = '//itoa(nx64)//', ny = '//itoa(ny64)// &
                         ', too large for integer(c_int32_t): pass integer(c_int64_t) variables')
      else
        nx = int(nx64, c_int32_t)
        ny = int(ny64, c_int32_t)
      end if
    end if
    call finish(status, ierr, 'dpsm_get_shape', g)
  end subroutine get_shape_i32

  ! ==== physics for real scenes =============================================

  !> dpsm_set_bedrock(g, zb[, ierr]): zb(nx, ny) or zb(nx*ny), a bed the sand
  !> cannot erode (a cell below it is lifted to it); without zb no bed.
  subroutine set_bedrock_r1(g, zb, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in), contiguous :: zb(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_bedrock', 'zb', shape(zb))
    if (status == DPSM_OK) status = c_dpsm_set_bedrock(g%ptr, zb)
    call finish(status, ierr, 'dpsm_set_bedrock', g)
  end subroutine set_bedrock_r1

  subroutine set_bedrock_r2(g, zb, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in), contiguous :: zb(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_bedrock', 'zb', shape(zb))
    if (status == DPSM_OK) status = c_dpsm_set_bedrock(g%ptr, zb)
    call finish(status, ierr, 'dpsm_set_bedrock', g)
  end subroutine set_bedrock_r2

  subroutine set_bedrock_none(g, ierr)
    type(dpsm_grid), intent(in) :: g
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_bedrock(g%ptr), ierr, 'dpsm_set_bedrock', g)
  end subroutine set_bedrock_none

  !> dpsm_set_repose_angle_field(g, theta_radians[, ierr]): an angle of repose
  !> per cell, theta_radians(nx, ny) or (nx*ny); without it the uniform angle.
  subroutine set_repose_angle_field_r1(g, theta_radians, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in), contiguous :: theta_radians(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_repose_angle_field', 'theta_radians', shape(theta_radians))
    if (status == DPSM_OK) status = c_dpsm_set_repose_angle_field(g%ptr, theta_radians)
    call finish(status, ierr, 'dpsm_set_repose_angle_field', g)
  end subroutine set_repose_angle_field_r1

  subroutine set_repose_angle_field_r2(g, theta_radians, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in), contiguous :: theta_radians(:, :)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    call clear_message(g)
    status = check_grid_shape(g, 'dpsm_set_repose_angle_field', 'theta_radians', shape(theta_radians))
    if (status == DPSM_OK) status = c_dpsm_set_repose_angle_field(g%ptr, theta_radians)
    call finish(status, ierr, 'dpsm_set_repose_angle_field', g)
  end subroutine set_repose_angle_field_r2

  subroutine set_repose_angle_field_none(g, ierr)
    type(dpsm_grid), intent(in) :: g
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_repose_angle_field(g%ptr), ierr, 'dpsm_set_repose_angle_field', g)
  end subroutine set_repose_angle_field_none

  !> dpsm_set_flux_exponent(g, p[, ierr]): p within [1, DPSM_MAX_FLUX_EXPONENT].
  subroutine dpsm_set_flux_exponent(g, p, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in) :: p
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_flux_exponent(g%ptr, p), ierr, 'dpsm_set_flux_exponent', g)
  end subroutine dpsm_set_flux_exponent

  !> dpsm_set_static_angle(g, radians[, ierr]): the angle at which sand at rest starts to move.
  subroutine dpsm_set_static_angle(g, radians, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(in) :: radians
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_static_angle(g%ptr, radians), ierr, 'dpsm_set_static_angle', g)
  end subroutine dpsm_set_static_angle

  ! ==== coupling: side levels, side outflows, face fluxes ====================

  !> dpsm_set_side_levels(g, side, levels[, ierr]): the level beyond each face
  !> of `side`, levels(ny) for DPSM_XMIN and DPSM_XMAX, levels(nx) for
  !> DPSM_YMIN and DPSM_YMAX (levels(1) on 1D and axisymmetric grids); without
  !> levels the side returns to 0. On a mesh, side DPSM_MESH_EDGE takes
  !> levels(nfaces), one per face (those of interior faces ignored).
  subroutine set_side_levels_r1(g, side, levels, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: side
    real(c_double), intent(in), contiguous :: levels(:)
    integer, intent(out), optional :: ierr
    integer(c_int) :: status
    integer(c_int64_t) :: nx, ny, faces, nfaces
    logical :: mesh
    call clear_message(g)
    status = c_dpsm_get_shape(g%ptr, nx, ny)
    if (status == DPSM_OK) then
      ! The C function refuses an unknown side, or one the grid or mesh does
      ! not have, before it reads any level.
      mesh = face_count(g, nfaces) == DPSM_OK
      faces = size(levels, kind=c_int64_t)
      if (mesh) then
        if (side == DPSM_MESH_EDGE) faces = nfaces
      else
        if (side == DPSM_XMIN .or. side == DPSM_XMAX) faces = ny
        if (side == DPSM_YMIN .or. side == DPSM_YMAX) faces = nx
      end if
      if (size(levels, kind=c_int64_t) /= faces) then
        status = DPSM_ERR_INVALID_SIZE
        if (mesh) then
          call set_message(g, 'dpsm_set_side_levels: levels has '//itoa(size(levels, kind=c_int64_t))// &
                           ' values but the mesh has '//itoa(faces)//' faces (one level per face for DPSM_MESH_EDGE)')
        else
          call set_message(g, 'dpsm_set_side_levels: levels has '//itoa(size(levels, kind=c_int64_t))// &
                           ' values but the side has '//itoa(faces)//' faces (ny for DPSM_XMIN and DPSM_XMAX, '// &
                           'nx for DPSM_YMIN and DPSM_YMAX)')
        end if
      else
        status = c_dpsm_set_side_levels(g%ptr, side, levels)
      end if
    end if
    call finish(status, ierr, 'dpsm_set_side_levels', g)
  end subroutine set_side_levels_r1

  subroutine set_side_levels_none(g, side, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: side
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_side_levels(g%ptr, side), ierr, 'dpsm_set_side_levels', g)
  end subroutine set_side_levels_none

  !> dpsm_get_side_outflow(g, side, value[, ierr]): the net mass that has left
  !> through `side` since the grid was made (negative where more came in).
  subroutine dpsm_get_side_outflow(g, side, value, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: side
    real(c_double), intent(out) :: value
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_get_side_outflow(g%ptr, side, value), ierr, 'dpsm_get_side_outflow', g)
  end subroutine dpsm_get_side_outflow

  !> dpsm_set_face_flux_recording(g, on[, ierr]): on = 1 records the volume
  !> each face carries in every step, 0 stops.
  subroutine dpsm_set_face_flux_recording(g, on, ierr)
    type(dpsm_grid), intent(in) :: g
    integer(c_int), intent(in) :: on
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_set_face_flux_recording(g%ptr, on), ierr, 'dpsm_set_face_flux_recording', g)
  end subroutine dpsm_set_face_flux_recording

  !> dpsm_get_face_fluxes(g, fx[, fy][, ierr]): the volume each face carried in
  !> the last step, positive towards increasing x (y): fx(nx+1, ny) or
  !> fx((nx+1)*ny), fx(i, j) the face on the low side of cell (i, j); fy(nx, ny+1)
  !> or fy(nx*(ny+1)) on 2D grids, left out on 1D and axisymmetric grids. On a
  !> mesh fx(nfaces) holds every face, positive from face_cells(1, f) to
  !> face_cells(2, f) of dpsm_get_mesh_faces, and fy is left out.
  subroutine get_face_fluxes_r1(g, fx, fy, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(out), contiguous :: fx(:)
    real(c_double), intent(out), contiguous, optional :: fy(:)
    integer, intent(out), optional :: ierr
    if (present(fy)) then
      call face_fluxes(g, shape(fx), fx, ierr, shape(fy), fy)
    else
      call face_fluxes(g, shape(fx), fx, ierr)
    end if
  end subroutine get_face_fluxes_r1

  subroutine get_face_fluxes_r2(g, fx, fy, ierr)
    type(dpsm_grid), intent(in) :: g
    real(c_double), intent(out), contiguous :: fx(:, :)
    real(c_double), intent(out), contiguous, optional :: fy(:, :)
    integer, intent(out), optional :: ierr
    if (present(fy)) then
      call face_fluxes(g, shape(fx), fx, ierr, shape(fy), fy)
    else
      call face_fluxes(g, shape(fx), fx, ierr)
    end if
  end subroutine get_face_fluxes_r2

  !> The shapes checked and the C function called, for both ranks (an absent
  !> fy reaches C as NULL).
  subroutine face_fluxes(g, fx_shape, fx, ierr, fy_shape, fy)
    type(dpsm_grid), intent(in) :: g
    integer, intent(in) :: fx_shape(:)
    real(c_double), intent(out) :: fx(*)
    integer, intent(out), optional :: ierr
    integer, intent(in), optional :: fy_shape(:)
    real(c_double), intent(out), optional :: fy(*)
    integer(c_int) :: status
    integer(c_int64_t) :: nfaces
    call clear_message(g)
    if (face_count(g, nfaces) == DPSM_OK) then
      ! A mesh: fx holds every face; C refuses an fy before it writes anything.
      status = check_face_shape(g, 'dpsm_get_face_fluxes', 'fx', nfaces, fx_shape)
      if (status == DPSM_OK) status = c_dpsm_get_face_fluxes(g%ptr, fx, fy)
      call finish(status, ierr, 'dpsm_get_face_fluxes', g)
      return
    end if
    status = check_grid_shape_plus(g, 'dpsm_get_face_fluxes', 'fx', 1, 0, fx_shape)
    if (status == DPSM_OK .and. present(fy_shape)) &
      status = check_grid_shape_plus(g, 'dpsm_get_face_fluxes', 'fy', 0, 1, fy_shape)
    if (status == DPSM_OK) status = c_dpsm_get_face_fluxes(g%ptr, fx, fy)
    call finish(status, ierr, 'dpsm_get_face_fluxes', g)
  end subroutine face_fluxes

  ! ==== restart files ========================================================

  !> A path as C wants it: without trailing blanks, NUL-terminated.
  function c_path(path) result(s)
    character(len=*), intent(in) :: path
    character(kind=c_char, len=:), allocatable :: s
    s = trim(path)//c_null_char
  end function c_path

  !> dpsm_save(g, path[, ierr]): writes everything needed to continue the run
  !> bit for bit to the file path (through path//'.tmp').
  subroutine dpsm_save(g, path, ierr)
    type(dpsm_grid), intent(in) :: g
    character(len=*), intent(in) :: path
    integer, intent(out), optional :: ierr
    call clear_message(g)
    call finish(c_dpsm_save(g%ptr, c_path(path)), ierr, 'dpsm_save', g)
  end subroutine dpsm_save

  !> dpsm_load(g, path[, ierr]): a new grid in g from a file written by
  !> dpsm_save (release it with dpsm_destroy). On failure g holds no grid and
  !> the message is dpsm_last_error() (without a grid), as for a failed create.
  subroutine dpsm_load(g, path, ierr)
    type(dpsm_grid), intent(out) :: g
    character(len=*), intent(in) :: path
    integer, intent(out), optional :: ierr
    type(c_ptr) :: ptr
    integer(c_int) :: status
    status = c_dpsm_load(c_path(path), ptr)
    call count_from_one(ptr, status)
    call adopt(g, ptr, status)
    call finish(status, ierr, 'dpsm_load')
  end subroutine dpsm_load

  ! ==== messages and versions ================================================

  !> The message of the last failed call on g, or '' if it succeeded. Without
  !> g (or with an empty g): the last failure in this thread that had no grid
  !> to keep it (a failed create), as dpsm_last_error(NULL) in C.
  function dpsm_last_error(g) result(message)
    type(dpsm_grid), intent(in), optional :: g
    character(len=:), allocatable :: message
    if (.not. present(g)) then
      message = last_error_without_grid()
      return
    end if
    if (associated(g%state)) then
      if (allocated(g%state%message)) then
        message = g%state%message
        return
      end if
    end if
    if (.not. c_associated(g%ptr)) then
      message = last_error_without_grid()
      return
    end if
    message = from_c_string(c_dpsm_last_error(g%ptr))
  end function dpsm_last_error

  !> A short name for a status code, e.g. 'DPSM_ERR_INVALID_VALUE'.
  function dpsm_status_string(status) result(name)
    integer(c_int), intent(in) :: status
    character(len=:), allocatable :: name
    name = from_c_string(c_dpsm_status_string(status))
  end function dpsm_status_string

  !> The version of the library actually linked, e.g. '0.1.0'.
  function dpsm_version_string() result(version)
    character(len=:), allocatable :: version
    version = from_c_string(c_dpsm_version_string())
  end function dpsm_version_string

  !> The version of the library actually linked as MAJOR*10000 + MINOR*100 + PATCH.
  integer(c_int) function dpsm_version_number()
    dpsm_version_number = c_dpsm_version_number()
  end function dpsm_version_number

end module dpsm
