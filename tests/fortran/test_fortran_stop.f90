! Without ierr a failed call stops the program with the library's message.
! tests/fortran/CMakeLists.txt runs it as
!   test_fortran_stop shape  -> a wrong array shape (found on the Fortran side)
!   test_fortran_stop value  -> a bad value (found by the C library)
!   test_fortran_stop create -> a failed create (message without a grid)
! and matches what error stop prints.
program test_fortran_stop
  use, intrinsic :: iso_c_binding, only: c_double
  use dpsm
  implicit none
  type(dpsm_grid) :: g
  character(len=16) :: what
  real(c_double) :: h(3, 5)

  call get_command_argument(1, what)
  if (what == 'create') call dpsm_create_2d(g, 0, 4, 1.0_c_double, 1.0_c_double)
  call dpsm_create_2d(g, 5, 3, 1.0_c_double, 1.0_c_double)
  h = 0
  select case (what)
  case ('shape')
    call dpsm_set_heights(g, h)
  case ('value')
    call dpsm_set_repose_angle(g, -1.0_c_double)
  end select
  print '(a)', 'not stopped'
end program test_fortran_stop
