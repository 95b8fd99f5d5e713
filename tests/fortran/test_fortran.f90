! Calls every routine of the Fortran module `dpsm` (bindings/fortran/dpsm.f90)
! with good and bad arguments and checks the results, so the module cannot
! drift from the C API. check_module.py also fails when a function of dpsm.h
! is not called here. Exits non-zero when any check fails.
program test_fortran
  use, intrinsic :: iso_c_binding, only: c_double, c_int, c_int8_t, c_int32_t, c_int64_t
  use, intrinsic :: iso_fortran_env, only: error_unit
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_positive_inf
  use dpsm
  implicit none

  integer :: failures = 0
  real(c_double), parameter :: pi = 3.14159265358979323846_c_double

  call test_versions_and_status()
  call test_create_failures()
  call test_2d()
  call test_regions()
  call test_cell_kinds_and_sources()
  call test_open_sides()
  call test_1d()
  call test_axisymmetric()
  call test_physics()
  call test_coupling()
  call test_restart()
  call test_meshes()
  call test_messages_count_from_one()
  call test_destroyed()

  if (failures > 0) then
    write (error_unit, '(i0, a)') failures, ' check(s) failed'
    error stop 1
  end if
  print '(a)', 'test_fortran: all checks passed'

contains

  subroutine expect(condition, what)
    logical, intent(in) :: condition
    character(len=*), intent(in) :: what
    if (.not. condition) then
      failures = failures + 1
      write (error_unit, '(2a)') 'FAILED: ', what
    end if
  end subroutine expect

  logical function close_to(a, b, rtol)
    real(c_double), intent(in) :: a, b, rtol
    close_to = abs(a - b) <= rtol*max(abs(a), abs(b), tiny(1.0_c_double))
  end function close_to

  !> The mass ledger closes: TOTAL == SOURCED + EXTERNAL - OUTFLOW.
  subroutine expect_ledger(g, what)
    type(dpsm_grid), intent(in) :: g
    character(len=*), intent(in) :: what
    real(c_double) :: total, sourced, external, outflow
    integer :: ierr(4)
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, total, ierr(1))
    call dpsm_get_mass(g, DPSM_MASS_SOURCED, sourced, ierr(2))
    call dpsm_get_mass(g, DPSM_MASS_EXTERNAL, external, ierr(3))
    call dpsm_get_mass(g, DPSM_MASS_OUTFLOW, outflow, ierr(4))
    call expect(all(ierr == DPSM_OK), what//': dpsm_get_mass')
    call expect(abs(total - (sourced + external - outflow)) <= 1e-12_c_double*max(abs(total), 1.0_c_double), &
                what//': TOTAL == SOURCED + EXTERNAL - OUTFLOW')
  end subroutine expect_ledger

  subroutine test_versions_and_status()
    character(len=:), allocatable :: s
    call expect(dpsm_version_string() == DPSM_HEADER_VERSION_STRING, 'dpsm_version_string() == header version')
    call expect(dpsm_version_number() == DPSM_HEADER_VERSION_NUMBER, 'dpsm_version_number() == header version')
    call expect(DPSM_HEADER_VERSION_NUMBER == DPSM_VERSION_MAJOR*10000 + DPSM_VERSION_MINOR*100 + DPSM_VERSION_PATCH, &
                'DPSM_HEADER_VERSION_NUMBER from MAJOR, MINOR, PATCH')
    s = dpsm_status_string(DPSM_OK)
    call expect(s == 'DPSM_OK', 'dpsm_status_string(DPSM_OK) is '//s)
    call expect(dpsm_status_string(DPSM_ERR_NULL_POINTER) == 'DPSM_ERR_NULL_POINTER', 'status NULL_POINTER')
    call expect(dpsm_status_string(DPSM_ERR_INVALID_VALUE) == 'DPSM_ERR_INVALID_VALUE', 'status INVALID_VALUE')
    call expect(dpsm_status_string(DPSM_ERR_INVALID_SIZE) == 'DPSM_ERR_INVALID_SIZE', 'status INVALID_SIZE')
    call expect(dpsm_status_string(DPSM_ERR_UNKNOWN_ENUM) == 'DPSM_ERR_UNKNOWN_ENUM', 'status UNKNOWN_ENUM')
    call expect(dpsm_status_string(DPSM_ERR_NOT_APPLICABLE) == 'DPSM_ERR_NOT_APPLICABLE', 'status NOT_APPLICABLE')
    call expect(dpsm_status_string(DPSM_ERR_WORK_LIMIT) == 'DPSM_ERR_WORK_LIMIT', 'status WORK_LIMIT')
    call expect(dpsm_status_string(DPSM_ERR_OUT_OF_MEMORY) == 'DPSM_ERR_OUT_OF_MEMORY', 'status OUT_OF_MEMORY')
    call expect(dpsm_status_string(DPSM_ERR_INTERNAL) == 'DPSM_ERR_INTERNAL', 'status INTERNAL')
    call expect(dpsm_status_string(DPSM_ERR_IO) == 'DPSM_ERR_IO', 'status IO')
    call expect(dpsm_status_string(DPSM_ERR_BAD_FILE) == 'DPSM_ERR_BAD_FILE', 'status BAD_FILE')
    call expect(dpsm_status_string(12345_c_int) == 'unknown status', 'dpsm_status_string(12345)')
  end subroutine test_versions_and_status

  subroutine test_create_failures()
    type(dpsm_grid) :: g
    integer :: ierr
    call dpsm_create_1d(g, 0_c_int64_t, 0.1_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_create_1d(nx = 0) fails with INVALID_SIZE')
    call expect(.not. dpsm_associated(g), 'a failed create leaves no grid')
    call expect(len(dpsm_last_error()) > 0, 'a failed create leaves a message in dpsm_last_error()')
    call expect(len(dpsm_last_error(g)) > 0, 'dpsm_last_error(empty grid) is dpsm_last_error(NULL)')
    call dpsm_create_2d(g, 4, 4, -1.0_c_double, 0.1_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_create_2d(dx < 0) fails with INVALID_VALUE')
    call dpsm_create_2d(g, 4_c_int64_t, -2_c_int64_t, 0.1_c_double, 0.1_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_create_2d(ny < 0) fails with INVALID_SIZE')
    call dpsm_create_axisymmetric(g, -3, 0.1_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_create_axisymmetric(nr < 0) fails with INVALID_SIZE')
    call dpsm_create_axisymmetric(g, 3_c_int64_t, 0.0_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_create_axisymmetric(dr = 0) fails with INVALID_VALUE')
    call expect(.not. dpsm_associated(g), 'still no grid')
  end subroutine test_create_failures

  subroutine test_2d()
    integer, parameter :: nx = 24, ny = 20
    real(c_double), parameter :: dx = 0.1_c_double, dy = 0.125_c_double, theta = 0.6_c_double, nu = 2.0_c_double
    type(dpsm_grid) :: g
    real(c_double) :: h(nx, ny), h2(nx, ny), flat(nx*ny), wrong(ny, nx), big(2*nx, ny)
    real(c_double) :: dt, value, total, external, slope_excess
    integer(c_int64_t) :: nx64, ny64
    integer(c_int32_t) :: nx32, ny32
    integer(c_int) :: threads, kind
    integer :: ierr, i, j
    character(len=:), allocatable :: message

    call dpsm_create_2d(g, nx, ny, dx, dy, ierr)
    call expect(ierr == DPSM_OK .and. dpsm_associated(g), 'dpsm_create_2d (default integers)')
    call dpsm_get_shape(g, nx64, ny64, ierr)
    call expect(ierr == DPSM_OK .and. nx64 == nx .and. ny64 == ny, 'dpsm_get_shape (c_int64_t)')
    call dpsm_get_shape(g, nx32, ny32)
    call expect(nx32 == nx .and. ny32 == ny, 'dpsm_get_shape (c_int32_t)')

    ! Parameters: good values pass, bad ones fail with the C status and a message.
    call dpsm_set_repose_angle(g, 2.0_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_repose_angle(2) fails')
    call expect(len(dpsm_last_error(g)) > 0, 'a failed call leaves a message on its grid')
    call dpsm_set_repose_angle(g, theta, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_repose_angle')
    call expect(dpsm_last_error(g) == '', 'a successful call clears the message')
    call dpsm_set_mobility(g, -1.0_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_mobility(-1) fails')
    call dpsm_set_mobility(g, nu)
    call dpsm_set_scheme(g, 7_c_int, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_set_scheme(7) fails')
    call dpsm_set_scheme(g, DPSM_SCHEME_PAIRWISE, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_scheme(PAIRWISE)')
    call dpsm_set_scheme(g, DPSM_SCHEME_ISOTROPIC, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_scheme(ISOTROPIC)')
    call dpsm_set_relaxation(g, 7_c_int, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_set_relaxation(7) fails')
    call dpsm_set_relaxation(g, DPSM_RELAX_TO_REST, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_relaxation(TO_REST)')
    call dpsm_set_relaxation(g, DPSM_RELAX_AUTO, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_relaxation(AUTO)')
    call dpsm_set_relaxation(g, DPSM_RELAX_LOCAL_STEPS, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_relaxation(LOCAL_STEPS)')
    call dpsm_set_relaxation(g, DPSM_RELAX_TIME_ACCURATE, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_relaxation(TIME_ACCURATE)')
    call dpsm_set_boundary(g, 9_c_int, DPSM_OPEN, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_set_boundary(side 9) fails')
    call dpsm_set_boundary(g, DPSM_XMIN, 5_c_int, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_set_boundary(kind 5) fails')
    call dpsm_set_boundary(g, DPSM_YMAX, DPSM_WALL, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_boundary(YMAX, WALL)')
    call dpsm_set_rest_tolerance(g, 0.0_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_rest_tolerance(0) fails')
    call dpsm_set_rest_tolerance(g, DPSM_DEFAULT_REST_TOLERANCE, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_rest_tolerance')
    call dpsm_set_max_substeps(g, 0, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_max_substeps(0) fails')
    call dpsm_set_max_substeps(g, DPSM_DEFAULT_MAX_SUBSTEPS, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_max_substeps (c_int64_t)')
    call dpsm_set_threads(g, -1_c_int, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_threads(-1) fails')
    call dpsm_set_threads(g, 2_c_int, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_threads(2)')
    call dpsm_get_threads(g, threads, ierr)
    call expect(ierr == DPSM_OK .and. threads == 2, 'dpsm_get_threads after dpsm_set_threads(2)')
    call dpsm_get_grid_kind(g, kind, ierr)
    call expect(ierr == DPSM_OK .and. kind == DPSM_GRID_2D, 'dpsm_get_grid_kind of a 2D grid')

    call dpsm_stable_dt(g, dt, ierr)
    call expect(ierr == DPSM_OK .and. close_to(dt, 1/(2*nu*cos(theta)*(1/dx**2 + 1/dy**2)), 1e-12_c_double), &
                'dpsm_stable_dt is 1 / (2 nu cos(theta) (1/dx^2 + 1/dy^2))')

    ! Before the first step every item of the step information is 0.
    call dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, value, ierr)
    call expect(ierr == DPSM_OK .and. value == 0, 'dpsm_get_step_info before a step')
    call dpsm_get_step_info(g, 10_c_int, value, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_get_step_info(10) fails')
    call dpsm_get_mass(g, 9_c_int, value, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_get_mass(9) fails')

    ! A steep cone, h(i, j) is cell (i-1, j-1): x fastest, as in C.
    do j = 1, ny
      do i = 1, nx
        h(i, j) = max(0.0_c_double, 1.5_c_double - 3*hypot((i - 12)*dx, (j - 10)*dy))
      end do
    end do
    call dpsm_set_heights(g, h, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_heights(h(nx, ny))')
    h2 = -1
    call dpsm_get_heights(g, h2, ierr)
    call expect(ierr == DPSM_OK .and. all(h2 == h), 'dpsm_get_heights(h(nx, ny)) gives back what was set')
    call dpsm_get_heights(g, flat, ierr)
    call expect(ierr == DPSM_OK .and. all(flat == reshape(h, [nx*ny])), 'dpsm_get_heights(h(nx*ny))')
    big = -1
    call dpsm_get_heights(g, big(1:2*nx:2, :), ierr)
    call expect(ierr == DPSM_OK .and. all(big(1:2*nx:2, :) == h) .and. all(big(2:2*nx:2, :) == -1), &
                'dpsm_get_heights into a non-contiguous section')
    call dpsm_set_heights(g, big(1:2*nx:2, :), ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_heights from a non-contiguous section')
    call dpsm_set_heights(g, flat, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_heights(h(nx*ny))')

    ! An array of the wrong shape is refused before C is called, with a clear message.
    wrong = 7
    call dpsm_set_heights(g, wrong, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_heights(h(ny, nx)) fails with INVALID_SIZE')
    message = dpsm_last_error(g)
    call expect(index(message, 'shape (20, 24)') > 0 .and. index(message, 'nx = 24, ny = 20') > 0, &
                'the shape message names both shapes: '//message)
    call dpsm_get_heights(g, h2, ierr)
    call expect(all(h2 == h), 'a refused dpsm_set_heights changes nothing')
    call expect(dpsm_last_error(g) == '', 'the next successful call clears the shape message')
    call dpsm_get_heights(g, flat(1:nx), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_get_heights(h(nx)) on a 2D grid fails')
    h2 = h
    h2(3, 4) = ieee_value(h2(3, 4), ieee_quiet_nan)
    call dpsm_set_heights(g, h2, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_heights with a NaN fails with INVALID_VALUE')

    call dpsm_get_mass(g, DPSM_MASS_TOTAL, total, ierr)
    call expect(ierr == DPSM_OK .and. close_to(total, sum(h)*dx*dy, 1e-12_c_double), 'TOTAL is sum h dx dy')
    call dpsm_get_mass(g, DPSM_MASS_EXTERNAL, external)
    call expect(close_to(external, total, 1e-12_c_double), 'EXTERNAL books dpsm_set_heights')

    ! To rest: walls all round, so the mass stays.
    call dpsm_step(g, 100.0_c_double, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_step')
    call dpsm_get_step_info(g, DPSM_INFO_AT_REST, value)
    call expect(value == 1, 'at rest after a long step')
    call dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, value)
    call expect(value >= 1, 'INFO_SUBSTEPS counts the sub-steps')
    call dpsm_get_step_info(g, DPSM_INFO_TIME_INTEGRATED, value)
    call expect(value > 0 .and. value <= 100, 'INFO_TIME_INTEGRATED is in (0, dt]')
    call dpsm_get_step_info(g, DPSM_INFO_CELL_UPDATES, value)
    call expect(value >= nx*ny, 'INFO_CELL_UPDATES counts at least one sweep')
    call dpsm_get_step_info(g, DPSM_INFO_RANK_CELL_UPDATES, slope_excess)
    call expect(slope_excess == value, 'INFO_RANK_CELL_UPDATES of a serial grid is INFO_CELL_UPDATES')
    call dpsm_get_step_info(g, DPSM_INFO_MESSAGES_SENT, value)
    call expect(value == 0, 'INFO_MESSAGES_SENT is 0 on a serial grid')
    call dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS_PER_EXCHANGE, value)
    call expect(value == 0, 'INFO_SUBSTEPS_PER_EXCHANGE is 0 on a serial grid')
    call dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS_EVALUATED, slope_excess)
    call dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, value)
    call expect(slope_excess == value, 'INFO_SUBSTEPS_EVALUATED is INFO_SUBSTEPS without local time steps')
    call dpsm_get_step_info(g, DPSM_INFO_MAX_EXCESS_SLOPE, slope_excess)
    call expect(slope_excess == 0, 'INFO_MAX_EXCESS_SLOPE is 0 at rest: no face carried sand')
    call dpsm_get_heights(g, h2)
    call expect(maxval(h2) < maxval(h), 'the cone slumped')
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, value)
    call expect(close_to(value, total, 1e-12_c_double), 'walls all round: the mass stays')
    call expect_ledger(g, 'after the slump')

    call dpsm_step(g, -1.0_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_step(-1) fails')
    call dpsm_destroy(g)
    call expect(.not. dpsm_associated(g), 'dpsm_destroy empties the grid')
  end subroutine test_2d

  subroutine test_regions()
    integer, parameter :: nx = 10, ny = 8
    type(dpsm_grid) :: g
    real(c_double) :: h(nx, ny), block(4, 5), block2(4, 5), row(20), wrong(5, 4)
    integer :: ierr, i, j

    call dpsm_create_2d(g, int(nx, c_int64_t), int(ny, c_int64_t), 1.0_c_double, 1.0_c_double)
    h = 0
    call dpsm_set_heights(g, h)
    do j = 1, 5
      do i = 1, 4
        block(i, j) = 0.01_c_double*(i + 10*j)
      end do
    end do
    ! The block of 4 x 5 cells from cell (2, 3), 0-based as in C: h(3:6, 4:8) here.
    call dpsm_set_heights_region(g, 2_c_int64_t, 3_c_int64_t, 4_c_int64_t, 5_c_int64_t, block, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_heights_region (c_int64_t, rank 2)')
    call dpsm_get_heights(g, h)
    call expect(all(h(3:6, 4:8) == block) .and. sum(h) == sum(block), 'the block lands on cells (2..5, 3..7)')
    block2 = 0
    call dpsm_get_heights_region(g, 2, 3, 4, 5, block2, ierr)
    call expect(ierr == DPSM_OK .and. all(block2 == block), 'dpsm_get_heights_region (default integers, rank 2)')
    row = 0.5_c_double
    call dpsm_add_heights_region(g, 2, 3, 4, 5, row, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_add_heights_region (default integers, rank 1)')
    call dpsm_add_heights_region(g, 2_c_int64_t, 3_c_int64_t, 4_c_int64_t, 5_c_int64_t, block, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_add_heights_region (c_int64_t, rank 2)')
    row = 0
    call dpsm_get_heights_region(g, 2_c_int64_t, 3_c_int64_t, 4_c_int64_t, 5_c_int64_t, row, ierr)
    call expect(ierr == DPSM_OK .and. all(abs(row - reshape(2*block + 0.5_c_double, [20])) < 1e-15_c_double), &
                'dpsm_get_heights_region (c_int64_t, rank 1) after two adds')
    call dpsm_set_heights_region(g, 0, 0, 4, 5, row, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_heights_region (default integers, rank 1)')
    call dpsm_get_heights(g, h)
    call expect(all(h(1:4, 1:5) == reshape(row, [4, 5])), 'the block lands on cells (0..3, 0..4)')
    call expect_ledger(g, 'after the blocks')

    wrong = 1
    call dpsm_set_heights_region(g, 2, 3, 4, 5, wrong, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_heights_region with h(nj, ni) fails')
    call expect(index(dpsm_last_error(g), 'ni = 4, nj = 5') > 0, 'the message names the block: '//dpsm_last_error(g))
    call dpsm_add_heights_region(g, 2, 3, 4, 5, row(1:19), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_add_heights_region with 19 values for 20 fails')
    call dpsm_get_heights_region(g, 8, 0, 4, 5, block2, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_get_heights_region off the grid fails in C')
    call expect(len(dpsm_last_error(g)) > 0, 'with a message')
    call dpsm_destroy(g)
  end subroutine test_regions

  subroutine test_cell_kinds_and_sources()
    integer, parameter :: nx = 12, ny = 10
    real(c_double), parameter :: dx = 0.5_c_double, rate = 0.01_c_double, dt = 0.5_c_double
    type(dpsm_grid) :: g
    integer(c_int8_t) :: kinds(nx, ny), flat_kinds(nx*ny)
    real(c_double) :: h(nx, ny), h2(nx, ny), q(nx, ny), sourced, stable, value
    integer :: ierr

    call dpsm_create_2d(g, nx, ny, dx, dx)
    h = 0.25_c_double
    h(5:6, 5:6) = 3
    call dpsm_set_heights(g, h)
    kinds = DPSM_CELL_SAND
    kinds(5:6, 5:6) = DPSM_CELL_WALL
    kinds(1, 1) = DPSM_CELL_OPEN
    call dpsm_set_cell_kinds(g, kinds, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_cell_kinds(kinds(nx, ny))')
    call expect_ledger(g, 'after turning cells into walls')
    kinds(2, 2) = 7
    call dpsm_set_cell_kinds(g, kinds, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_set_cell_kinds with a kind 7 fails')
    call dpsm_set_cell_kinds(g, flat_kinds(1:nx), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_cell_kinds(kinds(nx)) on a 2D grid fails')
    kinds(2, 2) = DPSM_CELL_SAND
    kinds(1, 1) = DPSM_CELL_SAND
    flat_kinds = reshape(kinds, [nx*ny])
    call dpsm_set_cell_kinds(g, flat_kinds, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_cell_kinds(kinds(nx*ny))')

    ! A uniform source: the wall cells neither gain nor move.
    q = rate
    call dpsm_set_source(g, q, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_source(q(nx, ny))')
    call dpsm_step(g, dt, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_step with a source')
    call dpsm_get_heights(g, h2)
    call expect(all(h2(5:6, 5:6) == 3), 'wall cells keep their height')
    call dpsm_get_mass(g, DPSM_MASS_SOURCED, sourced)
    call expect(close_to(sourced, rate*dt*(nx*ny - 4)*dx*dx, 1e-12_c_double), &
                'SOURCED is rate * dt * area of the sand cells')
    call expect_ledger(g, 'after the source')
    call dpsm_set_source(g, reshape(q, [nx*ny]), ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_source(q(nx*ny))')
    call dpsm_set_source(g, q(1:nx, 1:ny - 1), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_source(q(nx, ny-1)) fails')

    ! A driven scene (a source that makes a face steep within the step) is
    ! limited by dpsm_set_max_substeps; the uniform source above, which
    ! cannot, is applied in closed form and is not.
    call dpsm_stable_dt(g, stable)
    call dpsm_set_max_substeps(g, 1, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_max_substeps (default integer)')
    call dpsm_step(g, 10*stable, ierr)
    call expect(ierr == DPSM_OK, 'a gentle source is not limited')
    call dpsm_get_mass(g, DPSM_MASS_SOURCED, sourced)
    q(3, 3) = 100
    call dpsm_set_source(g, q, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_source with a steep cell')
    call dpsm_get_heights(g, h)
    call dpsm_step(g, 10*stable, ierr)
    call expect(ierr == DPSM_ERR_WORK_LIMIT, 'a driven step over the sub-step limit fails with WORK_LIMIT')
    call expect(len(dpsm_last_error(g)) > 0, 'with a message')
    call dpsm_get_heights(g, h2)
    call expect(all(h2 == h), 'the refused step changes nothing')

    ! No source: the step is no longer driven, and SOURCED stays.
    call dpsm_set_source(g, ierr=ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_source without q removes the source')
    call dpsm_step(g, 10*stable, ierr)
    call expect(ierr == DPSM_OK, 'the same step without a source passes')
    call dpsm_get_mass(g, DPSM_MASS_SOURCED, value)
    call expect(close_to(value, sourced, 1e-12_c_double), 'SOURCED unchanged without a source')

    call dpsm_set_cell_kinds(g, ierr=ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_cell_kinds without kinds makes every cell sand')
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, value)
    call dpsm_get_heights(g, h)
    call expect(close_to(value, sum(h)*dx*dx, 1e-12_c_double), 'every cell counts again')
    call expect_ledger(g, 'after all sand again')
    call dpsm_destroy(g)
  end subroutine test_cell_kinds_and_sources

  subroutine test_open_sides()
    integer, parameter :: n = 16
    type(dpsm_grid) :: g
    real(c_double) :: h(n, n), outflow
    call dpsm_create_2d(g, n, n, 0.1_c_double, 0.1_c_double)
    call dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN)
    call dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN)
    call dpsm_set_boundary(g, DPSM_YMIN, DPSM_OPEN)
    call dpsm_set_boundary(g, DPSM_YMAX, DPSM_OPEN)
    h = 2
    call dpsm_set_heights(g, h)
    call dpsm_step(g, 1e3_c_double)
    call dpsm_get_mass(g, DPSM_MASS_OUTFLOW, outflow)
    call expect(outflow > 0, 'sand leaves through open sides')
    call expect_ledger(g, 'open sides')
    call dpsm_destroy(g)
  end subroutine test_open_sides

  subroutine test_1d()
    integer, parameter :: nx = 30
    real(c_double), parameter :: dx = 0.2_c_double
    type(dpsm_grid) :: g
    real(c_double) :: h(nx), h2(nx), dt, total
    integer(c_int64_t) :: n1, n2
    integer(c_int) :: kind
    integer :: ierr
    call dpsm_create_1d(g, int(nx, c_int64_t), dx, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_1d (c_int64_t)')
    call dpsm_get_shape(g, n1, n2)
    call expect(n1 == nx .and. n2 == 1, 'a 1D grid has ny = 1')
    call dpsm_get_grid_kind(g, kind)
    call expect(kind == DPSM_GRID_1D, 'dpsm_get_grid_kind of a 1D grid')
    call dpsm_stable_dt(g, dt)
    call expect(close_to(dt, dx**2/(2*DPSM_DEFAULT_MOBILITY*cos(DPSM_DEFAULT_REPOSE_ANGLE)), 1e-12_c_double), &
                '1D: dpsm_stable_dt is dx^2 / (2 nu cos(theta)) with the defaults')
    call dpsm_set_boundary(g, DPSM_YMIN, DPSM_OPEN, ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, '1D: a y side is not applicable')
    call dpsm_destroy(g)
    call dpsm_create_1d(g, nx, dx) ! default integer
    call dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN)
    h = 1
    h(1:5) = 4
    call dpsm_set_heights(g, h)
    call dpsm_step(g, 1e3_c_double)
    call dpsm_get_heights(g, h2)
    call expect(h2(1) < 4 .and. all(h2 >= 0), '1D: the step moved sand')
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, total)
    call expect(close_to(total, sum(h2)*dx, 1e-12_c_double), '1D: TOTAL is sum h dx')
    call expect_ledger(g, '1D')
    call dpsm_destroy(g)
  end subroutine test_1d

  subroutine test_axisymmetric()
    integer, parameter :: nr = 20
    real(c_double), parameter :: dr = 0.05_c_double
    type(dpsm_grid) :: g
    real(c_double) :: h(nr), dt, total, volume
    integer(c_int) :: kind
    integer :: ierr, i
    call dpsm_create_axisymmetric(g, nr, dr, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_axisymmetric (default integers)')
    call dpsm_destroy(g)
    call dpsm_create_axisymmetric(g, int(nr, c_int64_t), dr, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_axisymmetric (c_int64_t)')
    call dpsm_get_grid_kind(g, kind, ierr)
    call expect(ierr == DPSM_OK .and. kind == DPSM_GRID_AXISYMMETRIC, 'dpsm_get_grid_kind of an axisymmetric grid')
    call dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN, ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, 'axisymmetric: the axis is not a boundary')
    call dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN, ierr)
    call expect(ierr == DPSM_OK, 'axisymmetric: the rim may be open')
    call dpsm_stable_dt(g, dt)
    call expect(close_to(dt, 3*dr**2/(8*cos(DPSM_DEFAULT_REPOSE_ANGLE)), 1e-12_c_double), &
                'axisymmetric: dpsm_stable_dt is 3 dr^2 / (8 nu cos(theta))')
    h = 1
    call dpsm_set_heights(g, h)
    volume = 0
    do i = 1, nr
      volume = volume + h(i)*2*pi*(i - 0.5_c_double)*dr*dr
    end do
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, total)
    call expect(close_to(total, volume, 1e-12_c_double), 'axisymmetric: TOTAL is sum h 2 pi r dr')
    call dpsm_step(g, 10.0_c_double)
    call expect_ledger(g, 'axisymmetric')
    call dpsm_destroy(g)
  end subroutine test_axisymmetric

  !> The physics of real scenes: a bed, an angle field, the flux exponent and
  !> the static angle, with good and bad arguments.
  subroutine test_physics()
    integer, parameter :: nx = 12, ny = 10
    type(dpsm_grid) :: g
    real(c_double) :: h(nx, ny), zb(nx, ny), theta(nx, ny), q(nx, ny), wrong(ny, nx), h2(nx, ny)
    real(c_double) :: unmet
    integer :: ierr
    call dpsm_create_2d(g, nx, ny, 0.1_c_double, 0.1_c_double)
    h = 1
    h(4:8, 4:7) = 2
    call dpsm_set_heights(g, h)

    zb = h - 0.01_c_double
    call dpsm_set_bedrock(g, zb, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_bedrock(zb(nx, ny))')
    call dpsm_set_bedrock(g, reshape(zb, [nx*ny]), ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_bedrock(zb(nx*ny))')
    zb(2, 3) = 1.0e60_c_double
    call dpsm_set_bedrock(g, zb, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_bedrock outside the supported range fails with INVALID_VALUE')
    call expect(index(dpsm_last_error(g), 'zb(2, 3) (cell i = 2, j = 3) = ') > 0, &
                'the message names the cell from 1: '//dpsm_last_error(g))
    wrong = 0
    call dpsm_set_bedrock(g, wrong, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_bedrock(zb(ny, nx)) fails with INVALID_SIZE')
    h2 = h - 1
    call dpsm_set_heights(g, h2, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'heights below the bed are refused')

    theta = 0.5_c_double
    theta(1:6, :) = 0.6_c_double
    call dpsm_set_repose_angle_field(g, theta, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_repose_angle_field(theta(nx, ny))')
    call dpsm_set_repose_angle_field(g, reshape(theta, [nx*ny]), ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_repose_angle_field(theta(nx*ny))')
    theta(3, 3) = 2
    call dpsm_set_repose_angle_field(g, theta, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_repose_angle_field with 2 radians fails')
    call dpsm_set_repose_angle_field(g, theta(1:nx, 1:ny - 1), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_repose_angle_field(theta(nx, ny-1)) fails')

    call dpsm_set_flux_exponent(g, DPSM_MAX_FLUX_EXPONENT + 0.5_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_flux_exponent above the maximum fails')
    call dpsm_set_flux_exponent(g, 0.5_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_flux_exponent(0.5) fails')
    call dpsm_set_flux_exponent(g, DPSM_DEFAULT_FLUX_EXPONENT, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_flux_exponent(DPSM_DEFAULT_FLUX_EXPONENT)')
    call dpsm_set_flux_exponent(g, 1.5_c_double, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_flux_exponent(1.5)')
    call dpsm_set_static_angle(g, 2.0_c_double, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_static_angle(2) fails')
    call dpsm_set_static_angle(g, 0.65_c_double, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_static_angle(0.65)')

    ! Erosion on a thin layer over the bed: what finds no sand is UNMET.
    q = -1
    call dpsm_set_source(g, q)
    call dpsm_step(g, 0.1_c_double, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_step with every physics feature')
    call dpsm_get_mass(g, DPSM_MASS_UNMET, unmet, ierr)
    call expect(ierr == DPSM_OK .and. unmet > 0, 'DPSM_MASS_UNMET counts erosion that found no sand')
    call expect(unmet <= 0.1_c_double*nx*ny*0.01_c_double, 'UNMET is at most the erosion asked for')
    call dpsm_get_heights(g, h2)
    call expect(all(h2 >= h - 0.01_c_double), 'the surface never goes below the bed')

    call dpsm_set_bedrock(g, ierr=ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_bedrock without zb removes the bed')
    call dpsm_set_repose_angle_field(g, ierr=ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_repose_angle_field without theta returns to the uniform angle')
    call dpsm_destroy(g)
  end subroutine test_physics

  !> What a host couples: levels beyond the sides, what left through each
  !> side, the face fluxes (2D and 1D), with good and bad arguments.
  subroutine test_coupling()
    integer, parameter :: nx = 8, ny = 5
    real(c_double), parameter :: d = 0.25_c_double
    type(dpsm_grid) :: g, line
    real(c_double) :: h(nx, ny), after(nx, ny), fx(nx + 1, ny), fy(nx, ny + 1), flat_x((nx + 1)*ny), flat_y(nx*(ny + 1))
    real(c_double) :: levels(ny), total, out, brought, line_fx(nx + 1), line_fy(2*nx)
    integer :: ierr, i, j
    logical :: balanced
    call dpsm_create_2d(g, nx, ny, d, d)
    call dpsm_get_face_fluxes(g, fx, fy, ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, 'dpsm_get_face_fluxes before recording fails with NOT_APPLICABLE')
    call dpsm_set_face_flux_recording(g, 2_c_int, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_face_flux_recording(2) fails with INVALID_VALUE')
    call dpsm_set_face_flux_recording(g, 1_c_int)

    ! An empty table beside a side held at 0.4: sand comes in, booked as negative outflow.
    levels = 0.4_c_double
    call dpsm_set_side_levels(g, DPSM_XMIN, levels, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_side_levels(levels(ny))')
    call dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN)
    h = 0
    call dpsm_step(g, 0.05_c_double)
    call dpsm_get_heights(g, after)
    call dpsm_get_face_fluxes(g, fx, fy, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_get_face_fluxes(fx(nx+1, ny), fy(nx, ny+1))')
    balanced = .true.
    do j = 1, ny
      do i = 1, nx
        brought = fx(i, j) - fx(i + 1, j) + fy(i, j) - fy(i, j + 1)
        balanced = balanced .and. abs(brought - (after(i, j) - h(i, j))*d*d) <= 1e-15_c_double
      end do
    end do
    call expect(balanced, 'each cell gained what its faces brought')
    call expect(all(fx(1, :) > 0), 'the faces of the raised side carry sand in (towards increasing x)')
    call dpsm_get_face_fluxes(g, flat_x, flat_y, ierr)
    call expect(ierr == DPSM_OK .and. all(flat_x == reshape(fx, [(nx + 1)*ny])) .and. &
                all(flat_y == reshape(fy, [nx*(ny + 1)])), 'dpsm_get_face_fluxes(flat arrays)')
    call dpsm_get_face_fluxes(g, h, fy, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_get_face_fluxes(fx(nx, ny)) fails with INVALID_SIZE')
    call expect(index(dpsm_last_error(g), 'fx(nx+1, ny)') > 0, 'the message names the shape: '//dpsm_last_error(g))
    call dpsm_get_face_fluxes(g, fx, ierr=ierr)
    call expect(ierr == DPSM_ERR_NULL_POINTER, 'dpsm_get_face_fluxes without fy on a 2D grid fails with NULL_POINTER')
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, total)
    call dpsm_get_side_outflow(g, DPSM_XMIN, out, ierr)
    call expect(ierr == DPSM_OK .and. close_to(out, -total, 1e-12_c_double), 'dpsm_get_side_outflow(XMIN) = -TOTAL')
    call dpsm_get_side_outflow(g, 7_c_int, out, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_get_side_outflow(7) fails with UNKNOWN_ENUM')
    call expect_ledger(g, 'coupling')

    call dpsm_set_side_levels(g, DPSM_YMIN, levels, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_side_levels(YMIN, levels(ny)) fails with INVALID_SIZE')
    levels(3) = ieee_value(levels(3), ieee_quiet_nan)
    call dpsm_set_side_levels(g, DPSM_XMAX, levels, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_side_levels with a NaN fails with INVALID_VALUE')
    call expect(index(dpsm_last_error(g), 'levels(3) (the face of cell j = 3 on side DPSM_XMAX) is NaN') > 0, &
                'the message names the face from 1: '//dpsm_last_error(g))
    call dpsm_set_side_levels(g, DPSM_XMIN, ierr=ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_side_levels without levels returns the side to 0')
    call dpsm_set_face_flux_recording(g, 0_c_int)
    call dpsm_get_face_fluxes(g, fx, fy, ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, 'dpsm_get_face_fluxes after recording stopped fails')
    call dpsm_destroy(g)

    ! A line: fx(nx+1) and no fy; its y sides are refused.
    call dpsm_create_1d(line, nx, d)
    call dpsm_set_face_flux_recording(line, 1_c_int)
    call dpsm_set_side_levels(line, DPSM_XMAX, [0.3_c_double], ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_side_levels(line, XMAX, levels(1))')
    call dpsm_set_side_levels(line, DPSM_YMIN, [0.3_c_double], ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE .or. ierr == DPSM_ERR_NOT_APPLICABLE, 'a line has no y side')
    call dpsm_get_side_outflow(line, DPSM_YMAX, out, ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, 'dpsm_get_side_outflow(line, YMAX) fails with NOT_APPLICABLE')
    call dpsm_set_boundary(line, DPSM_XMAX, DPSM_OPEN)
    call dpsm_step(line, 1.0_c_double)
    call dpsm_get_face_fluxes(line, line_fx, ierr=ierr)
    call expect(ierr == DPSM_OK .and. line_fx(nx + 1) < 0, 'dpsm_get_face_fluxes(line, fx(nx+1)): sand comes in')
    call dpsm_get_face_fluxes(line, line_fx, line_fy, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'a line given fy fails with INVALID_VALUE')
    call dpsm_destroy(line)
  end subroutine test_coupling

  !> Restart files: a saved and loaded grid continues bit for bit; missing,
  !> unwritable and damaged files fail with IO or BAD_FILE and no grid.
  subroutine test_restart()
    integer, parameter :: nx = 16, ny = 12
    character(len=*), parameter :: path = 'test_fortran_restart.dpsm'
    character(len=64) :: padded
    type(dpsm_grid) :: g, loaded
    real(c_double) :: h(nx, ny), h2(nx, ny), q(nx, ny), a, b
    integer :: ierr, i, j, unit, quantity
    logical :: same
    call dpsm_create_2d(g, nx, ny, 0.1_c_double, 0.1_c_double)
    do j = 1, ny
      do i = 1, nx
        h(i, j) = max(0.0_c_double, 1.2_c_double - 2*hypot((i - 8)*0.1_c_double, (j - 6)*0.1_c_double))
      end do
    end do
    call dpsm_set_heights(g, h)
    call dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN)
    q = 0.01_c_double
    call dpsm_set_source(g, q)
    call dpsm_set_static_angle(g, 0.6_c_double)
    call dpsm_step(g, 0.05_c_double)

    padded = path ! trailing blanks are dropped
    call dpsm_save(g, padded, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_save: '//dpsm_last_error(g))
    call dpsm_load(loaded, path, ierr)
    call expect(ierr == DPSM_OK .and. dpsm_associated(loaded), 'dpsm_load: '//dpsm_last_error())
    do i = 1, 3
      call dpsm_step(g, 0.05_c_double)
      call dpsm_step(loaded, 0.05_c_double)
    end do
    call dpsm_get_heights(g, h)
    call dpsm_get_heights(loaded, h2)
    call expect(all(h == h2), 'the loaded grid continues with the same heights')
    same = .true.
    do quantity = DPSM_MASS_TOTAL, DPSM_MASS_UNMET
      call dpsm_get_mass(g, quantity, a)
      call dpsm_get_mass(loaded, quantity, b)
      same = same .and. a == b
    end do
    call expect(same, 'and the same ledger')
    call dpsm_destroy(loaded)

    call dpsm_load(loaded, 'no-such-file.dpsm', ierr)
    call expect(ierr == DPSM_ERR_IO .and. .not. dpsm_associated(loaded), 'dpsm_load of a missing file fails with IO')
    call expect(index(dpsm_last_error(), 'no-such-file.dpsm') > 0, 'the message names the file: '//dpsm_last_error())
    call dpsm_save(g, '/nonexistent-dir/x', ierr)
    call expect(ierr == DPSM_ERR_IO, 'dpsm_save into a missing directory fails with IO')
    call expect(index(dpsm_last_error(g), '/nonexistent-dir/x') > 0, 'the message names the path')
    call dpsm_save(loaded, path, ierr)
    call expect(ierr == DPSM_ERR_NULL_POINTER, 'dpsm_save of no grid fails with NULL_POINTER')

    ! Not a restart file.
    open (newunit=unit, file=path, access='stream', form='unformatted', status='replace')
    write (unit) 'not a restart file'
    close (unit)
    call dpsm_load(loaded, path, ierr)
    call expect(ierr == DPSM_ERR_BAD_FILE .and. .not. dpsm_associated(loaded), &
                'dpsm_load of another file fails with BAD_FILE')
    call expect(index(dpsm_last_error(), 'not a dpsm restart file') > 0, 'and says so: '//dpsm_last_error())
    open (newunit=unit, file=path, status='old')
    close (unit, status='delete')
    call dpsm_destroy(g)
  end subroutine test_restart

  !> The library's messages name cells and array positions as this program
  !> writes them, from 1, on every grid the module creates or loads;
  !> dpsm_set_index_base(g, 0) gives C's.
  subroutine test_messages_count_from_one()
    integer, parameter :: nx = 3, ny = 3
    type(dpsm_grid) :: g, line, loaded
    integer(c_int8_t) :: kinds(nx, ny)
    real(c_double) :: h(nx, ny), block(2, 2), hl(5)
    integer :: ierr
    call dpsm_create_2d(g, nx, ny, 0.1_c_double, 0.1_c_double)
    kinds = DPSM_CELL_SAND
    kinds(3, 3) = 9
    call dpsm_set_cell_kinds(g, kinds, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_set_cell_kinds with kinds(3,3) = 9 fails with UNKNOWN_ENUM')
    call expect(index(dpsm_last_error(g), 'kinds(3, 3) (cell i = 3, j = 3) = 9') > 0, &
                'the message names kinds(3, 3) and cell i = 3, j = 3: '//dpsm_last_error(g))
    h = 0
    h(1, 2) = ieee_value(h(1, 2), ieee_quiet_nan)
    call dpsm_set_heights(g, h, ierr)
    call expect(index(dpsm_last_error(g), 'h(1, 2) (cell i = 1, j = 2) is NaN') > 0, &
                'dpsm_set_heights names h(1, 2): '//dpsm_last_error(g))
    ! A block's positions count within the block, its cells on the grid.
    block = 0
    block(2, 1) = ieee_value(block(2, 1), ieee_positive_inf)
    call dpsm_set_heights_region(g, 1, 1, 2, 2, block, ierr)
    call expect(index(dpsm_last_error(g), 'h(2, 1) (cell i = 3, j = 2) is +Inf') > 0, &
                'dpsm_set_heights_region names the block position and the cell: '//dpsm_last_error(g))
    call dpsm_set_index_base(g, 2_c_int, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_index_base(2) fails with INVALID_VALUE')
    call dpsm_set_index_base(g, 0_c_int, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_index_base(0)')
    call dpsm_set_cell_kinds(g, kinds, ierr)
    call expect(index(dpsm_last_error(g), 'kinds[8] (cell i = 2, j = 2) = 9') > 0, &
                'with base 0 the message is C''s: '//dpsm_last_error(g))
    call dpsm_set_index_base(g, 1_c_int, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_index_base(1)')

    ! A grid loaded from a restart file counts from 1 too.
    h = 1
    call dpsm_set_heights(g, h)
    call dpsm_save(g, 'test_fortran_index_base.dpsm', ierr)
    call expect(ierr == DPSM_OK, 'dpsm_save: '//dpsm_last_error(g))
    call dpsm_load(loaded, 'test_fortran_index_base.dpsm', ierr)
    call expect(ierr == DPSM_OK, 'dpsm_load: '//dpsm_last_error())
    call dpsm_set_cell_kinds(loaded, kinds, ierr)
    call expect(index(dpsm_last_error(loaded), 'kinds(3, 3) (cell i = 3, j = 3) = 9') > 0, &
                'a loaded grid counts from 1: '//dpsm_last_error(loaded))
    call dpsm_destroy(loaded)
    call dpsm_destroy(g)

    call dpsm_create_1d(line, 5, 0.1_c_double)
    hl = 0
    hl(4) = -1.0e60_c_double
    call dpsm_set_heights(line, hl, ierr)
    call expect(index(dpsm_last_error(line), 'h(4) (cell i = 4, j = 1) = ') > 0, &
                'a line names h(4): '//dpsm_last_error(line))
    call dpsm_destroy(line)
    call dpsm_create_axisymmetric(line, 5, 0.1_c_double)
    call dpsm_set_heights(line, hl, ierr)
    call expect(index(dpsm_last_error(line), 'h(4) (cell i = 4, j = 1)') > 0, &
                'an axisymmetric grid names h(4): '//dpsm_last_error(line))
    call dpsm_destroy(line)
  end subroutine test_messages_count_from_one

  !> Meshes: the three constructors with 1-based indices (good and bad, C's
  !> messages counting from 1 as the host does), their faces 1-based,
  !> per-face kinds, levels and fluxes, a restart, the _indexed constructors
  !> from 0 and 1, and the mesh routines refused on a grid.
  subroutine test_meshes()
    type(dpsm_grid) :: g, grid, loaded
    real(c_double) :: node_xy(2, 9), h(4), after(4), h2(4, 1), levels(12), fx(12), fx2(12, 1), fy(12)
    real(c_double) :: out, total, total0, brought(4)
    integer(c_int64_t) :: cell_start(5), cell_nodes(16), bad_nodes(16), nx, ny, nfaces, faces(2, 12), back(2, 12)
    integer(c_int32_t) :: nf32, faces32(2, 12)
    integer(c_int8_t) :: kinds(12)
    integer(c_int) :: kind
    integer :: ierr, i, j, f
    character(len=:), allocatable :: message

    ! A 2 x 2 quad mesh of unit squares over 9 nodes: node 1 + i + 3j at (i, j);
    ! cell c's nodes counter-clockwise, cell_start from 1 as a Fortran host holds it.
    do j = 0, 2
      do i = 0, 2
        node_xy(:, 1 + i + 3*j) = [real(i, c_double), real(j, c_double)]
      end do
    end do
    cell_start = [1, 5, 9, 13, 17]
    cell_nodes = [1, 2, 5, 4, 2, 3, 6, 5, 4, 5, 8, 7, 5, 6, 9, 8]
    call dpsm_create_mesh(g, 9_c_int64_t, node_xy, 4_c_int64_t, cell_start, cell_nodes, ierr)
    call expect(ierr == DPSM_OK .and. dpsm_associated(g), 'dpsm_create_mesh (c_int64_t): '//dpsm_last_error())
    call dpsm_get_shape(g, nx, ny)
    call expect(nx == 4 .and. ny == 1, 'dpsm_get_shape of a mesh is (ncells, 1)')
    call dpsm_get_face_count(g, nfaces, ierr)
    call expect(ierr == DPSM_OK .and. nfaces == 12, 'dpsm_get_face_count: 4 interior faces and 8 on the edge')
    call dpsm_get_face_count(g, nf32, ierr)
    call expect(ierr == DPSM_OK .and. nf32 == 12, 'dpsm_get_face_count (c_int32_t)')
    call dpsm_get_grid_kind(g, kind, ierr)
    call expect(ierr == DPSM_OK .and. kind == DPSM_GRID_MESH, 'dpsm_get_grid_kind of a mesh')
    faces = -7
    call dpsm_get_mesh_faces(g, faces, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_get_mesh_faces (c_int64_t)')
    ! Faces as they first appear, cell by cell, edge by edge: cell 1's edges
    ! 1-2 (edge), 2-5 (cell 2), 5-4 (cell 3), 4-1 (edge); then cell 2's new ones...
    call expect(all(faces(2, [1, 4, 5, 6, 9, 10, 11, 12]) == 0), 'edge faces have b = 0: '//ints(faces(2, :)))
    call expect(all(faces(1, [1, 4]) == 1) .and. all(faces(1, [5, 6]) == 2) .and. all(faces(1, [9, 10]) == 3) &
                .and. all(faces(1, [11, 12]) == 4), 'edge faces name their cell, 1-based: '//ints(faces(1, :)))
    call expect(same_pair(faces(:, 2), 1, 2) .and. same_pair(faces(:, 3), 1, 3) .and. same_pair(faces(:, 7), 2, 4) &
                .and. same_pair(faces(:, 8), 3, 4), 'interior faces join their cells, 1-based')
    faces32 = -7
    call dpsm_get_mesh_faces(g, faces32, ierr)
    call expect(ierr == DPSM_OK .and. all(faces32 == faces), 'dpsm_get_mesh_faces (c_int32_t)')
    call dpsm_get_mesh_faces(g, faces(:, 1:11), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_get_mesh_faces(face_cells(2, 11)) fails with INVALID_SIZE')
    call expect(index(dpsm_last_error(g), 'face_cells(2, nfaces)') > 0, 'with a message: '//dpsm_last_error(g))

    ! Per-cell arrays hold ncells values: h(ncells) or h(ncells, 1).
    h = [2.0_c_double, 0.0_c_double, 0.0_c_double, 0.0_c_double]
    call dpsm_set_heights(g, h, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_heights(h(ncells)) on a mesh')
    call dpsm_get_heights(g, h2, ierr)
    call expect(ierr == DPSM_OK .and. all(h2(:, 1) == h), 'dpsm_get_heights(h(ncells, 1)) on a mesh')
    call dpsm_set_heights(g, node_xy(1, :), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_heights(h(9)) on a mesh of 4 cells fails')
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, total0)
    call expect(close_to(total0, 2.0_c_double, 1e-12_c_double), 'a mesh: TOTAL is sum h * area')

    ! A collapse between walls, its face fluxes balancing each cell's change.
    call dpsm_set_face_flux_recording(g, 1_c_int)
    call dpsm_step(g, 0.05_c_double, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_step on a mesh')
    call dpsm_get_heights(g, after)
    call dpsm_get_face_fluxes(g, fx, ierr=ierr)
    call expect(ierr == DPSM_OK, 'dpsm_get_face_fluxes(fx(nfaces)) on a mesh')
    brought = 0
    do f = 1, 12
      brought(faces(1, f)) = brought(faces(1, f)) - fx(f)
      if (faces(2, f) > 0) brought(faces(2, f)) = brought(faces(2, f)) + fx(f)
    end do
    call expect(all(abs(brought - (after - h)) <= 1e-14_c_double) .and. after(1) < 2, &
                'each cell gained what its faces brought (positive from a to b)')
    call expect(all(fx([1, 4, 5, 6, 9, 10, 11, 12]) == 0), 'walls carry nothing')
    call dpsm_get_face_fluxes(g, fx2, ierr=ierr)
    call expect(ierr == DPSM_OK .and. all(fx2(:, 1) == fx), 'dpsm_get_face_fluxes(fx(nfaces, 1)) on a mesh')
    call dpsm_get_face_fluxes(g, fx, fy, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_get_face_fluxes with fy on a mesh fails with INVALID_VALUE')
    call dpsm_get_face_fluxes(g, fx(1:5), ierr=ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_get_face_fluxes(fx(5)) on a mesh of 12 faces fails')
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, total)
    call expect(close_to(total, total0, 1e-12_c_double), 'walls all round the mesh: the mass stays')

    ! The edge: levels and kinds per face (those of interior faces ignored).
    levels = 5
    call dpsm_set_side_levels(g, DPSM_MESH_EDGE, levels, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_side_levels(DPSM_MESH_EDGE, levels(nfaces))')
    call dpsm_set_side_levels(g, DPSM_MESH_EDGE, levels(1:4), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_side_levels(DPSM_MESH_EDGE, levels(4)) fails')
    call dpsm_set_side_levels(g, DPSM_XMIN, levels(1:1), ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, 'a mesh has no side DPSM_XMIN')
    kinds = int(DPSM_WALL, c_int8_t)
    kinds(1) = int(DPSM_OPEN, c_int8_t) ! the lower edge of cell 1
    kinds(2) = 9                        ! an interior face: ignored
    call dpsm_set_edge_kinds(g, kinds, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_edge_kinds(kinds(nfaces))')
    kinds(12) = 9
    call dpsm_set_edge_kinds(g, kinds, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_set_edge_kinds with a kind 9 on the edge fails')
    call expect(index(dpsm_last_error(g), 'kinds(12) (face 12, on the domain edge) = 9') > 0, &
                'a later message names the face as the host numbers it: '//dpsm_last_error(g))
    h2(:, 1) = h
    h2(3, 1) = ieee_value(h2(3, 1), ieee_quiet_nan)
    call dpsm_set_heights(g, h2, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_set_heights with a NaN fails on a mesh')
    call expect(index(dpsm_last_error(g), 'h(3) (cell 3) is NaN') > 0, &
                'dpsm_set_heights names the cell as the host numbers it: '//dpsm_last_error(g))
    call dpsm_set_edge_kinds(g, kinds(1:11), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_set_edge_kinds(kinds(11)) fails with INVALID_SIZE')
    call dpsm_step(g, 1.0_c_double)
    call dpsm_get_side_outflow(g, DPSM_MESH_EDGE, out, ierr)
    call expect(ierr == DPSM_OK .and. out < 0, 'sand comes in through the open face (outside at 5)')
    call expect_ledger(g, 'a mesh with an open face')
    call dpsm_set_edge_kinds(g, ierr=ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_edge_kinds without kinds: every edge a wall')
    call dpsm_set_boundary(g, DPSM_MESH_EDGE, DPSM_OPEN, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_set_boundary(DPSM_MESH_EDGE, DPSM_OPEN)')
    call dpsm_set_heights_region(g, 0, 0, 1, 1, h(1:1), ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, 'a mesh has no blocks')
    ! A restart keeps the mesh's numbering from 1.
    call dpsm_save(g, 'test_fortran_mesh.dpsm', ierr)
    call expect(ierr == DPSM_OK, 'dpsm_save of a mesh: '//dpsm_last_error(g))
    call dpsm_load(loaded, 'test_fortran_mesh.dpsm', ierr)
    call expect(ierr == DPSM_OK, 'dpsm_load of a mesh: '//dpsm_last_error())
    call dpsm_get_mesh_faces(loaded, back)
    call expect(all(back == faces), 'the loaded mesh lists its faces 1-based: '//ints(back(1, :)))
    call dpsm_set_edge_kinds(loaded, kinds, ierr)
    call expect(ierr == DPSM_ERR_UNKNOWN_ENUM, 'dpsm_set_edge_kinds with a kind 9 fails on the loaded mesh')
    call expect(index(dpsm_last_error(loaded), '(face 12, on') > 0, &
                'the loaded mesh names its faces 1-based: '//dpsm_last_error(loaded))
    call dpsm_destroy(loaded)
    open (newunit=f, file='test_fortran_mesh.dpsm', status='old')
    close (f, status='delete')
    call dpsm_destroy(g)

    ! The _indexed constructors: from 1 as dpsm_create_mesh, from 0 with C's
    ! numbering (and faces from 0, -1 on the edge); any other start refused.
    call dpsm_create_mesh_indexed(g, 1, 9_c_int64_t, node_xy, 4_c_int64_t, cell_start, cell_nodes, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_mesh_indexed(start_index = 1): '//dpsm_last_error())
    call dpsm_get_mesh_faces(g, back)
    call expect(all(back == faces), 'dpsm_create_mesh_indexed from 1 has the faces of dpsm_create_mesh')
    call dpsm_destroy(g)
    call dpsm_create_mesh_indexed(g, 0, 9, node_xy, 4, int(cell_start - 1, c_int32_t), int(cell_nodes - 1, c_int32_t), &
                                  ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_mesh_indexed(start_index = 0): '//dpsm_last_error())
    call dpsm_get_mesh_faces(g, back)
    call expect(all(back == faces - 1), 'from 0 the faces come back from 0, -1 on the edge: '//ints(back(2, :)))
    call dpsm_destroy(g)
    call dpsm_create_mesh_indexed(g, 2, 9_c_int64_t, node_xy, 4_c_int64_t, cell_start, cell_nodes, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE .and. .not. dpsm_associated(g), &
                'dpsm_create_mesh_indexed(start_index = 2) fails with INVALID_VALUE')
    call expect(index(dpsm_last_error(), 'start_index = 2') > 0, &
                'dpsm_create_mesh_indexed(start_index = 2) fails: '//dpsm_last_error())
    call dpsm_create_mesh_indexed(g, 0, 9_c_int64_t, node_xy, 4_c_int64_t, cell_start - 1, cell_nodes(1:15) - 1, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_create_mesh_indexed with 15 node indices for 16 fails')
    call expect(index(dpsm_last_error(), 'cell_nodes has 15 values but cell_start(ncells+1) = 16') > 0, &
                'from 0 the Fortran side names the sizes: '//dpsm_last_error())

    ! Default integers.
    call dpsm_create_mesh(g, 9, node_xy, 4, int(cell_start, c_int32_t), int(cell_nodes, c_int32_t), ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_mesh (default integers)')
    call dpsm_destroy(g)

    ! Bad input: node 10 of 9, node 0, a cell of 2 nodes, a node repeated: C's
    ! messages count from 1 and quote the host's values.
    bad_nodes = cell_nodes
    bad_nodes(3) = 10
    call dpsm_create_mesh(g, 9_c_int64_t, node_xy, 4_c_int64_t, cell_start, bad_nodes, ierr)
    message = dpsm_last_error()
    call expect(ierr == DPSM_ERR_INVALID_VALUE .and. .not. dpsm_associated(g), &
                'dpsm_create_mesh with node 10 of 9 fails with INVALID_VALUE')
    call expect(index(message, 'dpsm_create_mesh_indexed: cell_nodes(3) = 10 is not a node index in [1, 9]') > 0, &
                'the message names the host''s array as the host numbers it: '//message)
    bad_nodes(3) = 0
    call dpsm_create_mesh(g, 9_c_int64_t, node_xy, 4_c_int64_t, cell_start, bad_nodes, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_create_mesh with node 0 fails with INVALID_VALUE')
    call expect(index(dpsm_last_error(), 'cell_nodes(3) = 0 is not a node index in [1, 9]') > 0, &
                'node 0 is no node from 1: '//dpsm_last_error())
    call dpsm_create_mesh(g, 9, node_xy, 4, [1, 5, 9, 13, 15], int(cell_nodes(1:14), c_int32_t), ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_create_mesh with a cell of 2 nodes fails with INVALID_VALUE')
    call expect(index(dpsm_last_error(), 'cell 4 has 2 nodes (cell_start(4) = 13, cell_start(5) = 15)') > 0, &
                'the degenerate cell is named 1-based: '//dpsm_last_error())
    bad_nodes = cell_nodes
    bad_nodes(10) = 4 ! cell 3 becomes 4, 4, 8, 7
    call dpsm_create_mesh(g, 9_c_int64_t, node_xy, 4_c_int64_t, cell_start, bad_nodes, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_create_mesh with a node repeated in a row fails')
    call expect(index(dpsm_last_error(), 'cell 3 repeats node 4') > 0, &
                'a repeated node is named 1-based: '//dpsm_last_error())
    call dpsm_create_mesh(g, 9_c_int64_t, node_xy, 4_c_int64_t, cell_start, cell_nodes(1:15), ierr)
    message = dpsm_last_error()
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_create_mesh with 15 node indices for 16 fails with INVALID_SIZE')
    call expect(index(message, 'cell_nodes has 15 values but cell_start(ncells+1)-1 = 16') > 0, &
                'the Fortran side names the sizes: '//message)
    call dpsm_create_mesh(g, 9_c_int64_t, node_xy(:, 1:8), 4_c_int64_t, cell_start, cell_nodes, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, &
                'dpsm_create_mesh with node_xy(2, 8) for 9 nodes fails: '//dpsm_last_error())
    call expect(index(dpsm_last_error(), 'node_xy(2, nnodes)') > 0, &
                'dpsm_create_mesh with node_xy(2, 8) for 9 nodes fails: '//dpsm_last_error())
    call dpsm_create_mesh(g, 0_c_int64_t, node_xy, 4_c_int64_t, cell_start, cell_nodes, ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, &
                'dpsm_create_mesh(nnodes = 0) fails in C: '//dpsm_last_error())
    call expect(index(dpsm_last_error(), 'nnodes') > 0, &
                'dpsm_create_mesh(nnodes = 0) fails in C: '//dpsm_last_error())
    call expect(.not. dpsm_associated(g), 'no mesh after the failures')

    ! The mesh routines on a grid.
    call dpsm_create_2d(grid, 3, 3, 1.0_c_double, 1.0_c_double)
    call dpsm_get_face_count(grid, nfaces, ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, 'dpsm_get_face_count on a grid fails with NOT_APPLICABLE')
    call dpsm_get_mesh_faces(grid, faces, ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, &
                'dpsm_get_mesh_faces on a grid fails with NOT_APPLICABLE: '//dpsm_last_error(grid))
    call expect(index(dpsm_last_error(grid), 'dpsm_get_mesh_faces') > 0, &
                'dpsm_get_mesh_faces on a grid fails with NOT_APPLICABLE: '//dpsm_last_error(grid))
    call dpsm_set_edge_kinds(grid, kinds, ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, 'dpsm_set_edge_kinds on a grid fails with NOT_APPLICABLE')
    call dpsm_set_boundary(grid, DPSM_MESH_EDGE, DPSM_OPEN, ierr)
    call expect(ierr == DPSM_ERR_NOT_APPLICABLE, 'a grid has no DPSM_MESH_EDGE')
    call dpsm_destroy(grid)

    call test_dual_mesh()
    call test_graph()
    call test_geographic_and_centres()
  end subroutine test_meshes

  !> The median dual of 2 triangles over the unit square: one cell per node.
  subroutine test_dual_mesh()
    type(dpsm_grid) :: g
    real(c_double) :: node_xy(2, 4), h(4), total
    integer(c_int64_t) :: tris(3, 2), nx, ny, nfaces
    integer(c_int64_t), allocatable :: faces(:, :)
    integer :: ierr
    node_xy = reshape([0.0_c_double, 0.0_c_double, 1.0_c_double, 0.0_c_double, &
                       1.0_c_double, 1.0_c_double, 0.0_c_double, 1.0_c_double], [2, 4])
    tris = reshape([1_c_int64_t, 2_c_int64_t, 3_c_int64_t, 1_c_int64_t, 3_c_int64_t, 4_c_int64_t], [3, 2])
    call dpsm_create_dual_mesh(g, 4_c_int64_t, node_xy, 2_c_int64_t, tris, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_dual_mesh (c_int64_t): '//dpsm_last_error())
    call dpsm_get_shape(g, nx, ny)
    call expect(nx == 4 .and. ny == 1, 'a dual mesh has one cell per node')
    call dpsm_get_face_count(g, nfaces)
    ! 5 triangle edges between node cells, then 2 halves of each of the 4 boundary edges.
    call expect(nfaces == 13, 'a dual mesh of 2 triangles has 5 + 8 faces')
    allocate (faces(2, nfaces))
    call dpsm_get_mesh_faces(g, faces)
    call expect(all(faces(2, 1:5) > 0) .and. all(faces(2, 6:13) == 0) .and. all(faces(1, :) >= 1) .and. &
                all(faces(1, :) <= 4), 'the triangle edges join node cells, 1-based, the halves lie on the edge')
    call expect(same_pair(faces(:, 1), 1, 2), 'the first face joins nodes 1 and 2')
    h = [1.0_c_double, 0.0_c_double, 0.0_c_double, 0.0_c_double]
    call dpsm_set_heights(g, h)
    call dpsm_step(g, 1.0_c_double)
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, total)
    ! Node 1 lies in both triangles: its cell has a third of their area, 1/3.
    call expect(close_to(total, 1/3.0_c_double, 1e-12_c_double), 'a node cell has a third of its triangles'' area')
    call expect_ledger(g, 'a dual mesh')
    call dpsm_destroy(g)
    call dpsm_create_dual_mesh(g, 4, node_xy, 2, int(tris, c_int32_t), ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_dual_mesh (default integers)')
    call dpsm_destroy(g)
    call dpsm_create_dual_mesh_indexed(g, 0, 4_c_int64_t, node_xy, 2_c_int64_t, tris - 1, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_dual_mesh_indexed(start_index = 0): '//dpsm_last_error())
    call dpsm_get_mesh_faces(g, faces)
    call expect(same_pair(faces(:, 1), 0, 1) .and. all(faces(2, 6:13) == -1), &
                'a dual mesh from 0 lists its faces from 0, -1 on the edge')
    call dpsm_destroy(g)
    call dpsm_create_dual_mesh_indexed(g, 1, 4, node_xy, 2, int(tris, c_int32_t), ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_dual_mesh_indexed(start_index = 1, default integers)')
    call dpsm_destroy(g)
    call dpsm_create_dual_mesh_indexed(g, -1, 4_c_int64_t, node_xy, 2_c_int64_t, tris, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_create_dual_mesh_indexed(start_index = -1) fails')
    call expect(index(dpsm_last_error(), 'start_index = -1') > 0, &
                'dpsm_create_dual_mesh_indexed(start_index = -1) fails: '//dpsm_last_error())
    tris(2, 2) = 5
    call dpsm_create_dual_mesh(g, 4_c_int64_t, node_xy, 2_c_int64_t, tris, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, &
                'dpsm_create_dual_mesh with node 5 of 4 fails, C naming it as the host does: '//dpsm_last_error())
    call expect(index(dpsm_last_error(), 'triangle_nodes(2, 2) (triangle 2) = 5 is not a node index in [1, 4]') > 0, &
                'dpsm_create_dual_mesh with node 5 of 4 fails, C naming it as the host does: '//dpsm_last_error())
    tris(2, 2) = 3
    call dpsm_create_dual_mesh(g, 4_c_int64_t, node_xy, 2_c_int64_t, tris(:, 1:1), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, &
                'dpsm_create_dual_mesh with 1 triangle for 2 fails: '//dpsm_last_error())
    call expect(index(dpsm_last_error(), 'triangle_nodes(3, ntriangles)') > 0, &
                'dpsm_create_dual_mesh with 1 triangle for 2 fails: '//dpsm_last_error())
  end subroutine test_dual_mesh

  !> Issue 36: meshes in longitude and latitude, and where each cell lies.
  !> The octant of the sphere between (0, 0), (90, 0) and (0, 90) as one
  !> triangle (a polygon and a dual) has the area pi R^2 / 2; a quad mesh's
  !> centres are its centroids, a 2D grid's its cell centres.
  subroutine test_geographic_and_centres()
    type(dpsm_grid) :: g
    real(c_double), parameter :: radius = 6371008.8_c_double, pi = 3.14159265358979323846_c_double
    real(c_double) :: lonlat(2, 3), xy(2, 4), area(4), quad_xy(2, 6), centre(2, 2), cell_area(2)
    integer(c_int64_t) :: start(2), nodes(3), tris(3, 1)
    integer :: ierr
    lonlat = reshape([0.0_c_double, 0.0_c_double, 90.0_c_double, 0.0_c_double, 0.0_c_double, 90.0_c_double], [2, 3])
    start = [1_c_int64_t, 4_c_int64_t]
    nodes = [1_c_int64_t, 2_c_int64_t, 3_c_int64_t]
    call dpsm_create_mesh_geographic(g, 1, 3_c_int64_t, lonlat, 1_c_int64_t, start, nodes, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_mesh_geographic: '//dpsm_last_error())
    call dpsm_get_cell_centres(g, cell_area=area(1:1), ierr=ierr)
    call expect(ierr == DPSM_OK .and. close_to(area(1), pi*radius**2/2, 1e-12_c_double), &
                'the octant has the area pi R^2 / 2 on the sphere')
    call dpsm_destroy(g)
    tris(:, 1) = [1_c_int64_t, 2_c_int64_t, 3_c_int64_t]
    call dpsm_create_dual_mesh_geographic(g, 1, 3, lonlat, 1, int(tris, c_int32_t), ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_dual_mesh_geographic (default integers): '//dpsm_last_error())
    call dpsm_get_cell_centres(g, xy(:, 1:3), area(1:3), ierr)
    call expect(ierr == DPSM_OK .and. close_to(sum(area(1:3)), pi*radius**2/2, 1e-12_c_double), &
                'the dual cells of the octant share its area')
    call expect(abs(xy(1, 2) - 90) < 1e-9_c_double .and. abs(xy(2, 3) - 90) < 1e-9_c_double, &
                'a geographic dual cell stands at its node, in degrees')
    call dpsm_destroy(g)
    lonlat(2, 3) = 91
    call dpsm_create_mesh_geographic(g, 1, 3_c_int64_t, lonlat, 1_c_int64_t, start, nodes, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'a latitude of 91 is refused')
    call expect(index(dpsm_last_error(), 'node_lonlat(2, 3)') > 0, &
                'a latitude of 91 is refused, named as Fortran holds it: '//dpsm_last_error())
    ! Two unit squares: centroids (0.5, 0.5) and (1.5, 0.5), areas 1.
    quad_xy = reshape([0.0_c_double, 0.0_c_double, 1.0_c_double, 0.0_c_double, 2.0_c_double, 0.0_c_double, &
                       0.0_c_double, 1.0_c_double, 1.0_c_double, 1.0_c_double, 2.0_c_double, 1.0_c_double], [2, 6])
    call dpsm_create_mesh(g, 6, quad_xy, 2, [1, 5, 9], [1, 2, 5, 4, 2, 3, 6, 5], ierr)
    call expect(ierr == DPSM_OK, 'two squares')
    call dpsm_get_cell_centres(g, centre, cell_area, ierr)
    call expect(ierr == DPSM_OK .and. all(abs(centre - reshape([0.5_c_double, 0.5_c_double, 1.5_c_double, &
                0.5_c_double], [2, 2])) < 1e-15_c_double) .and. all(abs(cell_area - 1) < 1e-15_c_double), &
                'dpsm_get_cell_centres: the squares'' centroids and areas')
    call dpsm_get_cell_centres(g, centre(:, 1:1), ierr=ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, 'dpsm_get_cell_centres refuses a cell_xy of one cell for two')
    call expect(index(dpsm_last_error(g), 'cell_xy(2, 2)') > 0, &
                'dpsm_get_cell_centres refuses a cell_xy of one cell for two: '//dpsm_last_error(g))
    call dpsm_get_cell_centres(g, ierr=ierr)
    call expect(ierr == DPSM_ERR_NULL_POINTER, 'dpsm_get_cell_centres without an array fails')
    call dpsm_destroy(g)
    call dpsm_create_2d(g, 2, 2, 0.5_c_double, 2.0_c_double)
    call dpsm_get_cell_centres(g, xy, area)
    call expect(all(abs(xy(:, 4) - [0.75_c_double, 3.0_c_double]) < 1e-15_c_double) .and. &
                all(abs(area - 1) < 1e-15_c_double), 'a 2D grid''s cell (2, 2) lies at (0.75, 3), area dx dy')
    call dpsm_destroy(g)
  end subroutine test_geographic_and_centres

  !> A graph of 2 unit squares side by side: one interior face, 6 on the edge.
  subroutine test_graph()
    type(dpsm_grid) :: g
    real(c_double) :: cell_xy(2, 2), area(2), face_xy(2, 7), length(7), h(2), fx(7), total
    integer(c_int64_t) :: face_cells(2, 7), back(2, 7), bad(2, 7), nx, ny, nfaces
    integer :: ierr
    cell_xy = reshape([0.5_c_double, 0.5_c_double, 1.5_c_double, 0.5_c_double], [2, 2])
    area = 1
    ! Face 1 between the cells; then cell 1's left, bottom and top; cell 2's right, bottom and top.
    face_cells = reshape([1_c_int64_t, 2_c_int64_t, 1_c_int64_t, 0_c_int64_t, 1_c_int64_t, 0_c_int64_t, &
                          1_c_int64_t, 0_c_int64_t, 2_c_int64_t, 0_c_int64_t, 2_c_int64_t, 0_c_int64_t, &
                          2_c_int64_t, 0_c_int64_t], [2, 7])
    face_xy = reshape([1.0_c_double, 0.5_c_double, 0.0_c_double, 0.5_c_double, 0.5_c_double, 0.0_c_double, &
                       0.5_c_double, 1.0_c_double, 2.0_c_double, 0.5_c_double, 1.5_c_double, 0.0_c_double, &
                       1.5_c_double, 1.0_c_double], [2, 7])
    length = 1
    call dpsm_create_graph(g, 2_c_int64_t, cell_xy, area, 7_c_int64_t, face_cells, face_xy, length, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_graph (c_int64_t): '//dpsm_last_error())
    call dpsm_get_shape(g, nx, ny)
    call dpsm_get_face_count(g, nfaces)
    call expect(nx == 2 .and. ny == 1 .and. nfaces == 7, 'a graph of 2 cells and 7 faces')
    call dpsm_get_mesh_faces(g, back)
    call expect(all(back == face_cells), 'dpsm_get_mesh_faces gives back the host''s faces, 1-based, 0 on the edge')
    h = [2.0_c_double, 0.0_c_double]
    call dpsm_set_heights(g, h)
    call dpsm_set_face_flux_recording(g, 1_c_int)
    call dpsm_step(g, 0.1_c_double)
    call dpsm_get_heights(g, h)
    call dpsm_get_face_fluxes(g, fx)
    call expect(h(2) > 0 .and. fx(1) > 0 .and. abs(fx(1) - h(2)) <= 1e-14_c_double, &
                'sand crosses face 1 from cell 1 to cell 2')
    call dpsm_get_mass(g, DPSM_MASS_TOTAL, total)
    call expect(close_to(total, 2.0_c_double, 1e-12_c_double), 'a graph: the mass stays')
    call dpsm_destroy(g)
    call dpsm_create_graph(g, 2, cell_xy, area, 7, int(face_cells, c_int32_t), face_xy, length, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_graph (default integers)')
    call dpsm_destroy(g)
    call dpsm_create_graph_indexed(g, 0, 2_c_int64_t, cell_xy, area, 7_c_int64_t, face_cells - 1, face_xy, length, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_graph_indexed(start_index = 0): '//dpsm_last_error())
    call dpsm_get_mesh_faces(g, back)
    call expect(all(back == face_cells - 1), 'a graph from 0 gives its faces back from 0, -1 on the edge')
    call dpsm_destroy(g)
    call dpsm_create_graph_indexed(g, 1, 2, cell_xy, area, 7, int(face_cells, c_int32_t), face_xy, length, ierr)
    call expect(ierr == DPSM_OK, 'dpsm_create_graph_indexed(start_index = 1, default integers)')
    call dpsm_destroy(g)
    call dpsm_create_graph_indexed(g, 2, 2_c_int64_t, cell_xy, area, 7_c_int64_t, face_cells, face_xy, length, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_create_graph_indexed(start_index = 2) fails')
    call expect(index(dpsm_last_error(), 'start_index = 2') > 0, &
                'dpsm_create_graph_indexed(start_index = 2) fails: '//dpsm_last_error())
    bad = face_cells
    bad(2, 1) = 3
    call dpsm_create_graph(g, 2_c_int64_t, cell_xy, area, 7_c_int64_t, bad, face_xy, length, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, &
                'dpsm_create_graph with cell 3 of 2 fails, C naming it as the host does: '//dpsm_last_error())
    call expect(index(dpsm_last_error(), &
                      'face 1: face_cells(2, 1) = 3 is not a cell index in [1, 2] nor 0 (the domain edge)') > 0, &
                'dpsm_create_graph with cell 3 of 2 fails, C naming it as the host does: '//dpsm_last_error())
    bad = face_cells
    bad(1, 2) = 0
    call dpsm_create_graph(g, 2_c_int64_t, cell_xy, area, 7_c_int64_t, bad, face_xy, length, ierr)
    call expect(ierr == DPSM_ERR_INVALID_VALUE, 'dpsm_create_graph with a = 0 (the edge) fails with INVALID_VALUE')
    call expect(index(dpsm_last_error(), 'face 2: face_cells(1, 2) = 0 is not a cell index in [1, 2]') > 0, &
                'a = 0 is named as the host wrote it: '//dpsm_last_error())
    call dpsm_create_graph(g, 2_c_int64_t, cell_xy, area, 7_c_int64_t, face_cells, face_xy, length(1:6), ierr)
    call expect(ierr == DPSM_ERR_INVALID_SIZE, &
                'dpsm_create_graph with face_length(6) for 7 faces fails: '//dpsm_last_error())
    call expect(index(dpsm_last_error(), 'face_length has 6 values') > 0, &
                'dpsm_create_graph with face_length(6) for 7 faces fails: '//dpsm_last_error())
    call expect(.not. dpsm_associated(g), 'no graph after the failures')
  end subroutine test_graph

  logical function same_pair(pair, a, b)
    integer(c_int64_t), intent(in) :: pair(2)
    integer, intent(in) :: a, b
    same_pair = (pair(1) == a .and. pair(2) == b) .or. (pair(1) == b .and. pair(2) == a)
  end function same_pair

  function ints(values) result(s)
    integer(c_int64_t), intent(in) :: values(:)
    character(len=:), allocatable :: s
    character(len=24) :: buffer
    integer :: k
    s = ''
    do k = 1, size(values)
      write (buffer, '(i0)') values(k)
      s = s//' '//trim(buffer)
    end do
  end function ints

  subroutine test_destroyed()
    type(dpsm_grid) :: g, empty
    real(c_double) :: value
    integer :: ierr
    call dpsm_create_1d(g, 4, 1.0_c_double)
    call dpsm_destroy(g, ierr)
    call expect(ierr == DPSM_OK .and. .not. dpsm_associated(g), 'dpsm_destroy(g, ierr)')
    call dpsm_destroy(g, ierr)
    call expect(ierr == DPSM_OK, 'destroying an empty grid does nothing')
    call dpsm_step(g, 1.0_c_double, ierr)
    call expect(ierr == DPSM_ERR_NULL_POINTER, 'a call on a destroyed grid fails with NULL_POINTER')
    call expect(len(dpsm_last_error(g)) > 0, 'with a message')
    call dpsm_get_mass(empty, DPSM_MASS_TOTAL, value, ierr)
    call expect(ierr == DPSM_ERR_NULL_POINTER, 'a call on a never-created grid fails with NULL_POINTER')
    call dpsm_set_heights(empty, [1.0_c_double], ierr)
    call expect(ierr == DPSM_ERR_NULL_POINTER, 'the shape check of an empty grid fails with NULL_POINTER')
  end subroutine test_destroyed

end program test_fortran
