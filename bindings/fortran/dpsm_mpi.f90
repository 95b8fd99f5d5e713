!> dpsm_mpi: the Fortran binding of include/dpsm/dpsm_mpi.h (distributed grids).
!>
!> Built with the MPI component only, into libdpsm_mpi_fortran together with
!> its own copy of module dpsm (over libdpsm_mpi, not libdpsm), whose .mod
!> files are installed in <includedir>/dpsm/fortran-mpi. A program uses both
!> modules: it creates its block with dpsm_create_2d_mpi and then calls the
!> routines of module dpsm on it, as on any grid.
!>
!>     call dpsm_create_2d_mpi(g, comm, nx_global, ny_global, i0, j0, nx_local, ny_local, dx, dy[, ierr])
!>
!> comm is the integer handle of a Fortran communicator: MPI_COMM_WORLD (or
!> any communicator) of `use mpi`, or comm%MPI_VAL of `use mpi_f08`. The
!> module itself needs no MPI module: the C side turns the handle into an
!> MPI_Comm (dpsm_create_2d_mpi_f, MPI_Comm_f2c). i0 and j0 are 0-based, as
!> every block offset of module dpsm; sizes are integer(c_int64_t) or default
!> integers. Without ierr a failure stops the program with the message.
!>
!>     call dpsm_load_mpi(g, comm, path[, ierr])
!>
!> reads back this rank's block of a distributed grid from the file path that
!> this rank wrote with dpsm_save (collective over comm, on as many ranks as
!> saved it; trailing blanks of path are dropped).
!>
!>     call dpsm_create_graph_mpi(g, comm, global_id, owner, cell_xy, cell_area, face_cells, face_xy, face_length[, ierr])
!>     call dpsm_create_mesh_mpi(g, comm, node_xy, cell_start, cell_nodes, global_id, owner[, ierr])
!>
!> this rank's part of a distributed mesh: its owned and ghost cells as the
!> host holds them, with the arrays of dpsm_create_graph and dpsm_create_mesh
!> (indices from 1, 0 for the domain edge in face_cells), global ids from 1
!> and owners as ranks of comm (from 0, as MPI counts); the counts are the
!> arrays' sizes. Messages name cells and global ids from 1. Collective over comm.
module dpsm_mpi
  use, intrinsic :: iso_c_binding, only: c_ptr, c_int, c_int32_t, c_int64_t, c_double, c_char, c_null_char
  use dpsm, only: dpsm_grid, dpsm_adopt_handle, dpsm_status_string, dpsm_last_error, DPSM_OK
  implicit none
  private

  public :: dpsm_create_2d_mpi, dpsm_load_mpi, dpsm_create_graph_mpi, dpsm_create_mesh_mpi

  interface dpsm_create_2d_mpi
    module procedure create_2d_mpi_i64, create_2d_mpi_i32
  end interface dpsm_create_2d_mpi

  interface
    ! MPI_Fint is a C int in Open MPI and MPICH (a default Fortran integer).
    function c_dpsm_create_2d_mpi_f(comm, nx_global, ny_global, i0, j0, nx_local, ny_local, dx, dy, out) &
        bind(C, name='dpsm_create_2d_mpi_f') result(status)
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int), value :: comm
      integer(c_int64_t), value :: nx_global, ny_global, i0, j0, nx_local, ny_local
      real(c_double), value :: dx, dy
      type(c_ptr), intent(out) :: out
      integer(c_int) :: status
    end function c_dpsm_create_2d_mpi_f

    function c_dpsm_create_graph_mpi_f(comm, ncells, global_id, owner, cell_xy, cell_area, nfaces, face_cells, &
                                       face_xy, face_length, out) bind(C, name='dpsm_create_graph_mpi_f') result(status)
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int), value :: comm
      integer(c_int64_t), value :: ncells, nfaces
      integer(c_int64_t), intent(in) :: global_id(*), face_cells(*)
      integer(c_int), intent(in) :: owner(*)
      real(c_double), intent(in) :: cell_xy(*), cell_area(*), face_xy(*), face_length(*)
      type(c_ptr), intent(out) :: out
      integer(c_int) :: status
    end function c_dpsm_create_graph_mpi_f

    function c_dpsm_create_mesh_mpi_f(comm, nnodes, node_xy, ncells, cell_start, cell_nodes, global_id, owner, out) &
        bind(C, name='dpsm_create_mesh_mpi_f') result(status)
      import :: c_int, c_int64_t, c_double, c_ptr
      integer(c_int), value :: comm
      integer(c_int64_t), value :: nnodes, ncells
      real(c_double), intent(in) :: node_xy(*)
      integer(c_int64_t), intent(in) :: cell_start(*), cell_nodes(*), global_id(*)
      integer(c_int), intent(in) :: owner(*)
      type(c_ptr), intent(out) :: out
      integer(c_int) :: status
    end function c_dpsm_create_mesh_mpi_f

    function c_dpsm_load_mpi_f(comm, path, out) bind(C, name='dpsm_load_mpi_f') result(status)
      import :: c_int, c_char, c_ptr
      integer(c_int), value :: comm
      character(kind=c_char), intent(in) :: path(*)
      type(c_ptr), intent(out) :: out
      integer(c_int) :: status
    end function c_dpsm_load_mpi_f
  end interface

contains

  !> dpsm_create_2d_mpi(g, comm, nx_global, ny_global, i0, j0, nx_local, ny_local, dx, dy[, ierr]):
  !> this rank's block [i0, i0+nx_local) x [j0, j0+ny_local) of a global
  !> nx_global x ny_global grid distributed over comm. Collective over comm.
  subroutine create_2d_mpi_i64(g, comm, nx_global, ny_global, i0, j0, nx_local, ny_local, dx, dy, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: comm
    integer(c_int64_t), intent(in) :: nx_global, ny_global, i0, j0, nx_local, ny_local
    real(c_double), intent(in) :: dx, dy
    integer, intent(out), optional :: ierr
    type(c_ptr) :: ptr
    integer(c_int) :: status
    status = c_dpsm_create_2d_mpi_f(int(comm, c_int), nx_global, ny_global, i0, j0, nx_local, ny_local, dx, dy, ptr)
    call dpsm_adopt_handle(g, ptr, status)
    if (present(ierr)) then
      ierr = int(status)
    else if (status /= DPSM_OK) then
      error stop 'dpsm_create_2d_mpi failed: '//dpsm_status_string(status)//': '//dpsm_last_error()
    end if
  end subroutine create_2d_mpi_i64

  subroutine create_2d_mpi_i32(g, comm, nx_global, ny_global, i0, j0, nx_local, ny_local, dx, dy, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: comm
    integer(c_int32_t), intent(in) :: nx_global, ny_global, i0, j0, nx_local, ny_local
    real(c_double), intent(in) :: dx, dy
    integer, intent(out), optional :: ierr
    call create_2d_mpi_i64(g, comm, int(nx_global, c_int64_t), int(ny_global, c_int64_t), int(i0, c_int64_t), &
                           int(j0, c_int64_t), int(nx_local, c_int64_t), int(ny_local, c_int64_t), dx, dy, ierr)
  end subroutine create_2d_mpi_i32

  !> dpsm_load_mpi(g, comm, path[, ierr]): this rank's block of the distributed
  !> grid saved by dpsm_save, from the file path this rank wrote. Collective
  !> over comm. On failure g holds no grid on any rank, and the message is
  !> dpsm_last_error() (without a grid).
  subroutine dpsm_load_mpi(g, comm, path, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: comm
    character(len=*), intent(in) :: path
    integer, intent(out), optional :: ierr
    type(c_ptr) :: ptr
    integer(c_int) :: status
    status = c_dpsm_load_mpi_f(int(comm, c_int), trim(path)//c_null_char, ptr)
    call dpsm_adopt_handle(g, ptr, status)
    if (present(ierr)) then
      ierr = int(status)
    else if (status /= DPSM_OK) then
      error stop 'dpsm_load_mpi failed: '//dpsm_status_string(status)//': '//dpsm_last_error()
    end if
  end subroutine dpsm_load_mpi

  !> dpsm_create_graph_mpi(g, comm, global_id, owner, cell_xy, cell_area, face_cells, face_xy, face_length[, ierr]):
  !> this rank's part of a mesh given as a finite-volume graph: ncells =
  !> size(global_id) local cells (cell_xy(2, ncells), cell_area(ncells)),
  !> nfaces = size(face_length) faces (face_cells(2, nfaces) from 1, 0 for the
  !> domain edge; face_xy(2, nfaces)). Collective over comm.
  subroutine dpsm_create_graph_mpi(g, comm, global_id, owner, cell_xy, cell_area, face_cells, face_xy, face_length, &
                                   ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: comm
    integer(c_int64_t), intent(in), contiguous :: global_id(:), face_cells(:, :)
    integer, intent(in), contiguous :: owner(:)
    real(c_double), intent(in), contiguous :: cell_xy(:, :), cell_area(:), face_xy(:, :), face_length(:)
    integer, intent(out), optional :: ierr
    type(c_ptr) :: ptr
    integer(c_int) :: status
    status = c_dpsm_create_graph_mpi_f(int(comm, c_int), size(global_id, kind=c_int64_t), global_id, int(owner, c_int), &
                                       cell_xy, cell_area, size(face_length, kind=c_int64_t), face_cells, face_xy, &
                                       face_length, ptr)
    call adopt(g, ptr, status, 'dpsm_create_graph_mpi', ierr)
  end subroutine dpsm_create_graph_mpi

  !> dpsm_create_mesh_mpi(g, comm, node_xy, cell_start, cell_nodes, global_id, owner[, ierr]):
  !> this rank's part of a mesh given as polygons: node_xy(2, nnodes),
  !> cell_start(ncells + 1) from 1, cell_nodes from 1, global_id(ncells) from
  !> 1, owner(ncells). Collective over comm.
  subroutine dpsm_create_mesh_mpi(g, comm, node_xy, cell_start, cell_nodes, global_id, owner, ierr)
    type(dpsm_grid), intent(out) :: g
    integer, intent(in) :: comm
    real(c_double), intent(in), contiguous :: node_xy(:, :)
    integer(c_int64_t), intent(in), contiguous :: cell_start(:), cell_nodes(:), global_id(:)
    integer, intent(in), contiguous :: owner(:)
    integer, intent(out), optional :: ierr
    type(c_ptr) :: ptr
    integer(c_int) :: status
    status = c_dpsm_create_mesh_mpi_f(int(comm, c_int), size(node_xy, 2, kind=c_int64_t), node_xy, &
                                      size(global_id, kind=c_int64_t), cell_start, cell_nodes, global_id, &
                                      int(owner, c_int), ptr)
    call adopt(g, ptr, status, 'dpsm_create_mesh_mpi', ierr)
  end subroutine dpsm_create_mesh_mpi

  subroutine adopt(g, ptr, status, name, ierr)
    type(dpsm_grid), intent(inout) :: g
    type(c_ptr), intent(in) :: ptr
    integer(c_int), intent(in) :: status
    character(len=*), intent(in) :: name
    integer, intent(out), optional :: ierr
    call dpsm_adopt_handle(g, ptr, status)
    if (present(ierr)) then
      ierr = int(status)
    else if (status /= DPSM_OK) then
      error stop name//' failed: '//dpsm_status_string(status)//': '//dpsm_last_error()
    end if
  end subroutine adopt

end module dpsm_mpi
