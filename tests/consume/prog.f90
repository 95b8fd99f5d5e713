! A small Fortran program built against an installed dpsm with
!     gfortran prog.f90 $(pkg-config --cflags --libs dpsm-fortran)
! (tests/consume/run.sh). It calls a few routines of module dpsm and checks
! their results; it stops with a non-zero code on any wrong one.
program consume_fortran
  use, intrinsic :: iso_c_binding, only: c_double, c_int64_t
  use dpsm
  implicit none
  integer, parameter :: nx = 40
  type(dpsm_grid) :: g
  real(c_double) :: h(nx), total, sourced, external, outflow
  integer(c_int64_t) :: n1, n2
  integer :: ierr

  if (dpsm_version_string() /= DPSM_HEADER_VERSION_STRING) error stop 'module and library versions differ'
  if (dpsm_version_number() /= DPSM_HEADER_VERSION_NUMBER) error stop 'module and library version numbers differ'

  call dpsm_create_1d(g, 0, 0.1_c_double, ierr)
  if (ierr /= DPSM_ERR_INVALID_SIZE .or. len(dpsm_last_error()) == 0) error stop 'a failed create'

  call dpsm_create_1d(g, nx, 0.1_c_double)
  call dpsm_get_shape(g, n1, n2)
  if (n1 /= nx .or. n2 /= 1) error stop 'dpsm_get_shape'
  call dpsm_set_repose_angle(g, 0.5_c_double)
  call dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN)
  h = 0
  h(1:20) = 4 ! more than a slope at the angle of repose can hold: some must leave
  call dpsm_set_heights(g, h)
  call dpsm_step(g, 1e4_c_double)
  call dpsm_get_heights(g, h)
  call dpsm_get_mass(g, DPSM_MASS_TOTAL, total)
  call dpsm_get_mass(g, DPSM_MASS_SOURCED, sourced)
  call dpsm_get_mass(g, DPSM_MASS_EXTERNAL, external)
  call dpsm_get_mass(g, DPSM_MASS_OUTFLOW, outflow)
  if (outflow <= 0) error stop 'no sand left through the open side'
  if (abs(total - (sourced + external - outflow)) > 1e-12_c_double*external) error stop 'the ledger does not close'
  if (h(1) >= 4) error stop 'the column did not slump'
  call dpsm_destroy(g)
  print '(a, a, a)', 'consume_fortran: dpsm ', dpsm_version_string(), ' ok'
end program consume_fortran
