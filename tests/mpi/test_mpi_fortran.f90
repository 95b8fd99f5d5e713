! The Fortran binding of the MPI component (module dpsm_mpi), under mpiexec:
! each rank owns a strip of columns of a 50 x 40 grid; after every step its
! block must equal, bit for bit, the same block of a serial run of the whole
! scene, and the global mass must match; a grid saved with dpsm_save and read
! back with dpsm_load_mpi must continue bit for bit, and a rank given another
! rank's file must fail on every rank; a decomposition with a gap must fail
! on every rank with a message that says so. A mesh of quads handed over by
! dpsm_create_mesh_mpi (strips of columns, one layer of ghosts, indices and
! global ids from 1) must equal the serial mesh bit for bit and exchange
! twice a sub-step (DPSM_INFO_SUBSTEPS_PER_EXCHANGE 0.5), and a global id
! out of range must fail on every rank naming it from 1.
program test_mpi_fortran
  use, intrinsic :: iso_c_binding, only: c_double, c_int64_t
  use mpi
  use dpsm
  use dpsm_mpi
  implicit none
  integer, parameter :: nx = 50, ny = 40
  type(dpsm_grid) :: g, serial, loaded
  integer :: ierr, rank, ranks, i, j, step, failures, total, i0, ni
  real(c_double) :: h(nx, ny), dt, mass_g, mass_s
  real(c_double), allocatable :: mine(:, :), ref(:, :)
  character(len=:), allocatable :: message
  character(len=64) :: path, other

  call MPI_Init(ierr)
  call MPI_Comm_rank(MPI_COMM_WORLD, rank, ierr)
  call MPI_Comm_size(MPI_COMM_WORLD, ranks, ierr)
  failures = 0

  ! This rank's strip of columns [i0, i0 + ni), uneven.
  i0 = rank*(nx/ranks) + min(rank, mod(nx, ranks))
  ni = nx/ranks
  if (rank < mod(nx, ranks)) ni = ni + 1

  do j = 1, ny
    do i = 1, nx
      h(i, j) = 0.0_c_double
      if ((i - 25)**2 + (j - 20)**2 < 100) h(i, j) = 12.0_c_double
    end do
  end do

  call dpsm_create_2d_mpi(g, MPI_COMM_WORLD, nx, ny, i0, 0, ni, ny, 1.0_c_double, 1.0_c_double)
  call dpsm_create_2d(serial, nx, ny, 1.0_c_double, 1.0_c_double)
  ! A distributed grid steps in time by default; its serial twin must too.
  call dpsm_set_relaxation(serial, DPSM_RELAX_TIME_ACCURATE)
  do i = DPSM_XMIN, DPSM_YMAX
    call dpsm_set_boundary(g, i, DPSM_OPEN)
    call dpsm_set_boundary(serial, i, DPSM_OPEN)
  end do
  call dpsm_set_heights(g, h(i0 + 1:i0 + ni, :))
  call dpsm_set_heights(serial, h)
  call dpsm_stable_dt(serial, dt)
  dt = 30*dt
  allocate (mine(ni, ny), ref(ni, ny))
  do step = 1, 4
    call dpsm_step(g, dt)
    call dpsm_step(serial, dt)
    call dpsm_get_heights(g, mine)
    call dpsm_get_heights_region(serial, i0, 0, ni, ny, ref)
    if (any(mine /= ref)) then
      failures = failures + 1
      print '(a,i0,a,i0,a,i0)', 'FAIL: rank ', rank, ' step ', step, ': cells differing from serial: ', &
        count(mine /= ref)
    end if
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, mass_g)
    call dpsm_get_mass(serial, DPSM_MASS_TOTAL, mass_s)
    if (abs(mass_g - mass_s) > 1e-12_c_double*abs(mass_s)) then
      failures = failures + 1
      print '(a,i0,a,2es25.17)', 'FAIL: rank ', rank, ' global mass differs: ', mass_g, mass_s
    end if
  end do
  call dpsm_destroy(serial)

  ! Saved, read back, and on for two more steps: bit for bit.
  write (path, '(a,i0,a,i0,a)') 'dpsm_mpi_fortran.', rank, 'of', ranks, '.dpsm'
  write (other, '(a,i0,a,i0,a)') 'dpsm_mpi_fortran.', mod(rank + 1, ranks), 'of', ranks, '.dpsm'
  call dpsm_save(g, path)
  call dpsm_load_mpi(loaded, MPI_COMM_WORLD, path)
  do step = 1, 2
    call dpsm_step(g, dt)
    call dpsm_step(loaded, dt)
    call dpsm_get_heights(g, mine)
    call dpsm_get_heights(loaded, ref)
    call dpsm_get_mass(g, DPSM_MASS_OUTFLOW, mass_g)
    call dpsm_get_mass(loaded, DPSM_MASS_OUTFLOW, mass_s)
    if (any(mine /= ref) .or. mass_g /= mass_s) then
      failures = failures + 1
      print '(a,i0,a,i0,a,i0,a,2es25.17)', 'FAIL: rank ', rank, ' step ', step, ' after the load: cells differing: ', &
        count(mine /= ref), ', outflow ', mass_g, mass_s
    end if
  end do
  call dpsm_destroy(loaded)
  if (ranks > 1) then
    call dpsm_load_mpi(loaded, MPI_COMM_WORLD, other, ierr)
    message = dpsm_last_error()
    if (ierr == DPSM_OK .or. index(message, 'holds the block of rank') == 0 .or. dpsm_associated(loaded)) then
      failures = failures + 1
      print '(a,i0,a,i0,2a)', 'FAIL: rank ', rank, ' another rank''s file gave status ', ierr, ' and message: ', message
    else if (rank == 0) then
      print '(2a)', 'refused on every rank: ', message
    end if
  end if
  call MPI_Barrier(MPI_COMM_WORLD, ierr)
  open (newunit=i, file=trim(path), status='old')
  close (i, status='delete')
  call dpsm_destroy(g)

  ! A gap: the last rank leaves out its last column.
  if (rank == ranks - 1) ni = ni - 1
  call dpsm_create_2d_mpi(g, MPI_COMM_WORLD, int(nx, c_int64_t), int(ny, c_int64_t), int(i0, c_int64_t), &
                          0_c_int64_t, int(ni, c_int64_t), int(ny, c_int64_t), 1.0_c_double, 1.0_c_double, ierr)
  message = dpsm_last_error()
  if (ierr == DPSM_OK .or. index(message, 'belongs to no rank') == 0 .or. dpsm_associated(g)) then
    failures = failures + 1
    print '(a,i0,a,i0,2a)', 'FAIL: rank ', rank, ' a gap gave status ', ierr, ' and message: ', message
  else if (rank == 0) then
    print '(2a)', 'refused on every rank: ', message
  end if

  call mesh_parts()

  call MPI_Allreduce(failures, total, 1, MPI_INTEGER, MPI_SUM, MPI_COMM_WORLD, ierr)
  if (rank == 0) print '(a,i0,a,i0)', 'test_mpi_fortran on ', ranks, ' ranks: failures ', total
  call MPI_Finalize(ierr)
  if (total /= 0) error stop 1
contains

  ! An m x m lattice of unit quads; rank r owns columns [c0, c0 + nc) and holds
  ! the columns beside them as ghosts; cells numbered row by row from 1.
  subroutine mesh_parts()
    integer, parameter :: m = 16
    real(c_double) :: node_xy(2, (m + 1)*(m + 1)), hs(m*m), x, y, per_exchange
    integer(c_int64_t) :: cell_start(m*m + 1), cell_nodes(4*m*m)
    integer(c_int64_t), allocatable :: part_start(:), part_nodes(:), global_id(:)
    integer, allocatable :: owner(:)
    real(c_double), allocatable :: hp(:)
    type(dpsm_grid) :: part, whole
    integer :: c0, nc, k, n, cell, column, row, local, s
    do row = 0, m
      do column = 0, m
        node_xy(:, 1 + column + (m + 1)*row) = [real(column, c_double), real(row, c_double) + 0.1_c_double*column]
      end do
    end do
    do row = 0, m - 1
      do column = 0, m - 1
        cell = 1 + column + m*row
        cell_start(cell) = 4*(cell - 1) + 1
        k = 1 + column + (m + 1)*row
        cell_nodes(4*(cell - 1) + 1:4*cell) = int([k, k + 1, k + m + 2, k + m + 1], c_int64_t)
        x = column + 0.5_c_double - m/2.0_c_double
        y = row + 0.5_c_double - m/2.0_c_double
        hs(cell) = 0.0_c_double
        if (x*x + y*y < 16.0_c_double) hs(cell) = 6.0_c_double
      end do
    end do
    cell_start(m*m + 1) = 4*m*m + 1
    c0 = rank*(m/ranks) + min(rank, mod(m, ranks))
    nc = m/ranks
    if (rank < mod(m, ranks)) nc = nc + 1
    n = 0
    do row = 0, m - 1
      do column = max(0, c0 - 1), min(m - 1, c0 + nc)
        n = n + 1
      end do
    end do
    allocate (part_start(n + 1), part_nodes(4*n), global_id(n), owner(n), hp(n))
    local = 0
    do row = 0, m - 1
      do column = max(0, c0 - 1), min(m - 1, c0 + nc)
        local = local + 1
        cell = 1 + column + m*row
        global_id(local) = cell
        owner(local) = rank
        if (column < c0) owner(local) = rank - 1
        if (column >= c0 + nc) owner(local) = rank + 1
        part_start(local) = 4*(local - 1) + 1
        part_nodes(4*(local - 1) + 1:4*local) = cell_nodes(4*(cell - 1) + 1:4*cell)
        hp(local) = hs(cell)
        if (owner(local) /= rank) hp(local) = -3.0_c_double  ! a ghost's value is replaced by its owner's
      end do
    end do
    part_start(n + 1) = 4*n + 1
    call dpsm_create_mesh_mpi(part, MPI_COMM_WORLD, node_xy, part_start, part_nodes, global_id, owner)
    call dpsm_create_mesh(whole, int((m + 1)*(m + 1), c_int64_t), node_xy, int(m*m, c_int64_t), cell_start, cell_nodes)
    call dpsm_set_boundary(part, DPSM_MESH_EDGE, DPSM_OPEN)
    call dpsm_set_boundary(whole, DPSM_MESH_EDGE, DPSM_OPEN)
    call dpsm_set_heights(part, hp)
    call dpsm_set_heights(whole, hs)
    do s = 1, 4
      call dpsm_step(part, 0.5_c_double)
      call dpsm_step(whole, 0.5_c_double)
      call dpsm_get_heights(part, hp)
      call dpsm_get_heights(whole, hs)
      if (any(hp /= hs(global_id))) then
        failures = failures + 1
        print '(a,i0,a,i0,a,i0)', 'FAIL: rank ', rank, ' mesh step ', s, ': cells differing from serial: ', &
          count(hp /= hs(global_id))
      end if
    end do
    ! One layer of ghosts: a ghost's gradient is its owner's to send, two exchanges a sub-step.
    call dpsm_get_step_info(part, DPSM_INFO_SUBSTEPS_PER_EXCHANGE, per_exchange)
    if ((ranks > 1 .and. per_exchange /= 0.5_c_double) .or. (ranks == 1 .and. per_exchange /= 8)) then
      failures = failures + 1
      print '(a,i0,a,f0.1)', 'FAIL: rank ', rank, ' one layer of ghosts gave sub-steps per exchange ', per_exchange
    end if
    call dpsm_destroy(part)
    call dpsm_destroy(whole)
    ! A global id beyond the mesh's m*m cells, named as Fortran counts.
    if (rank == 0) global_id(1) = m*m + 1
    call dpsm_create_mesh_mpi(part, MPI_COMM_WORLD, node_xy, part_start, part_nodes, global_id, owner, ierr)
    message = dpsm_last_error()
    if (ierr == DPSM_OK .or. index(message, 'numbered from 1 without gaps') == 0 .or. dpsm_associated(part)) then
      failures = failures + 1
      print '(a,i0,a,i0,2a)', 'FAIL: rank ', rank, ' a global id out of range gave status ', ierr, ' and message: ', &
        message
    else if (rank == 0) then
      print '(2a)', 'refused on every rank: ', message
    end if
  end subroutine mesh_parts

end program test_mpi_fortran
