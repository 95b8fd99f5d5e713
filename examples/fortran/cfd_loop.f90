! A CFD time loop coupled to dpsm, in Fortran: the shape a real adapter takes.
!
! A toy "flow solver" blows wind along +x over a sand pile on a flat bed.
! Every time step it
!   1. computes the bed shear stress from the current surface: speed-up on the
!      windward slope, no stress in the separation bubble behind the crest
!      (the shadow of the surface at 14 degrees down the wind);
!   2. turns it into a sand flux that relaxes over a saturation length towards
!      q_sat = Q0 (tau/tau0)^(3/2), and into the deposition / erosion rate
!      -dq/dx (the Exner equation): erosion upwind of the crest, deposition in
!      its lee;
!   3. hands that rate to dpsm as the source, calls dpsm_step, which lets the
!      over-steepened lee avalanche at the angle of repose, and reads the
!      heights back for the next flow solve.
! Every few steps it prints the mass balance: dpsm's ledger (TOTAL == SOURCED
! + EXTERNAL - OUTFLOW) next to the host's own sum of what it deposited.
!
! usage: dpsm-cfd-loop [nsteps]          (default 300)
program cfd_loop
  use, intrinsic :: iso_c_binding, only: c_double
  use dpsm
  implicit none

  ! The grid (metres) and the run (seconds).
  integer, parameter :: nx = 100, ny = 40
  real(c_double), parameter :: dx = 0.5_c_double, dy = 0.5_c_double
  real(c_double), parameter :: dt = 1.0_c_double
  real(c_double), parameter :: pi = 3.14159265358979323846_c_double
  real(c_double), parameter :: theta = 32*pi/180 ! angle of repose
  ! The toy flow: flux on the flat bed (m^2/s), speed-up per unit slope,
  ! shadow angle, saturation length (m).
  real(c_double), parameter :: q0 = 0.01_c_double, speedup = 3.0_c_double
  real(c_double), parameter :: shadow_slope = 0.25_c_double ! tan(14 degrees)
  real(c_double), parameter :: saturation_length = 2.0_c_double

  type(dpsm_grid) :: g
  real(c_double) :: h(nx, ny), source(nx, ny)
  real(c_double) :: total, sourced, external, outflow, host_sourced, residual, substeps, stable
  real(c_double) :: crest0
  integer :: nsteps, n, i, j, ierr
  character(len=32) :: arg

  nsteps = 300
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg)
    read (arg, *) nsteps
  end if

  ! ---- set up dpsm once -----------------------------------------------------
  ! [setup]
  call dpsm_create_2d(g, nx, ny, dx, dy) ! without ierr a failure stops with the message
  call dpsm_set_repose_angle(g, theta)
  call dpsm_set_boundary(g, DPSM_XMIN, DPSM_OPEN) ! the bed runs on beyond the ends
  call dpsm_set_boundary(g, DPSM_XMAX, DPSM_OPEN) ! the y sides stay walls
  ! A host that already keeps every core busy (MPI ranks, its own threads)
  ! gives dpsm one thread; so does a grid this small.
  call dpsm_set_threads(g, 1)
  do j = 1, ny
    do i = 1, nx
      h(i, j) = 2.5_c_double*exp(-(((i - 30)*dx)**2 + ((j - ny/2)*dy)**2)/(2*3.0_c_double**2))
    end do
  end do
  call dpsm_set_heights(g, h) ! booked as EXTERNAL mass
  ! [setup]
  call dpsm_stable_dt(g, stable)
  crest0 = crest_x(h)
  host_sourced = 0

  print '(a, a)', 'dpsm ', dpsm_version_string()
  print '(a, i0, a, i0, a, f6.3, a, f6.3, a, f0.1, a)', 'wind over a sand pile: ', nx, ' x ', ny, &
    ' cells, dt = ', dt, ' s, stable sub-step ', stable, ' s, angle of repose ', theta*180/pi, ' deg'
  print '(a6, a8, 5a14, a10, a9)', 'step', 't [s]', 'TOTAL', 'SOURCED', 'host sourced', 'OUTFLOW', &
    'residual', 'sub-steps', 'crest x'

  ! ---- the time loop --------------------------------------------------------
  ! [loop]
  do n = 1, nsteps
    call flow_solver(h, source)                ! 1-2: the host's physics
    call dpsm_set_source(g, source)            ! 3: deposition > 0, erosion < 0
    call dpsm_step(g, dt, ierr)
    if (ierr /= DPSM_OK) then
      print '(a, i0, a, a)', 'step ', n, ' failed: ', dpsm_last_error(g)
      error stop 1
    end if
    call dpsm_get_heights(g, h)                ! the surface the next flow solve sees
    host_sourced = host_sourced + sum(source)*dt*dx*dy

    if (mod(n, max(nsteps/10, 1)) == 0 .or. n == nsteps) then
      call dpsm_get_mass(g, DPSM_MASS_TOTAL, total)
      call dpsm_get_mass(g, DPSM_MASS_SOURCED, sourced)
      call dpsm_get_mass(g, DPSM_MASS_EXTERNAL, external)
      call dpsm_get_mass(g, DPSM_MASS_OUTFLOW, outflow)
      call dpsm_get_step_info(g, DPSM_INFO_SUBSTEPS, substeps)
      residual = total - (sourced + external - outflow)
      print '(i6, f8.1, 4f14.6, es14.2, f10.0, f9.2)', n, n*dt, total, sourced, host_sourced, outflow, &
        residual, substeps, crest_x(h)
      if (abs(residual) > 1e-9_c_double*abs(external)) error stop 'the mass ledger does not close'
      if (abs(sourced - host_sourced) > 1e-9_c_double*abs(external)) &
        error stop 'dpsm did not deposit what the host handed it'
    end if
  end do
  ! [loop]

  print '(a, f0.2, a, f0.2, a)', 'the crest moved downwind from x = ', crest0, ' m to x = ', crest_x(h), ' m'
  print '(a, f5.3, a, f5.3, a)', 'steepest lee slope along the wind ', &
    maxval((h(1:nx - 1, :) - h(2:nx, :))/dx), ' (tan(theta) = ', tan(theta), ': dpsm avalanches the lee)'
  if (crest_x(h) <= crest0) error stop 'the pile did not move downwind'
  call dpsm_destroy(g)

contains

  !> The toy flow solver: from the surface h, the deposition (> 0) and
  !> erosion (< 0) rate, in height per second.
  subroutine flow_solver(h, rate)
    real(c_double), intent(in) :: h(:, :)
    real(c_double), intent(out) :: rate(:, :)
    real(c_double) :: q(0:size(h, 1)), tau, slope, shadow
    integer :: i, j, m
    m = size(h, 1)
    do j = 1, size(h, 2)
      q(0) = q0 ! saturated inflow: the flat bed upwind neither gains nor loses
      shadow = -huge(1.0_c_double)
      do i = 1, m
        ! Bed shear stress relative to the flat bed.
        slope = (h(min(i + 1, m), j) - h(max(i - 1, 1), j))/((min(i + 1, m) - max(i - 1, 1))*dx)
        tau = max(0.0_c_double, 1 + speedup*slope)
        ! The separation bubble: below the line dropping from upwind surface at the shadow slope.
        shadow = shadow - shadow_slope*dx
        if (h(i, j) < shadow) then
          tau = 0
        else
          shadow = h(i, j)
        end if
        ! The flux leaving cell i downwind relaxes towards saturation.
        q(i) = q(i - 1) + (q0*tau**1.5_c_double - q(i - 1))*dx/saturation_length
      end do
      rate(:, j) = (q(0:m - 1) - q(1:m))/dx ! Exner: dh/dt = -dq/dx
    end do
  end subroutine flow_solver

  !> The x of the highest cell of the pile.
  real(c_double) function crest_x(h)
    real(c_double), intent(in) :: h(:, :)
    integer :: top(2)
    top = maxloc(h)
    crest_x = (top(1) - 0.5_c_double)*dx
  end function crest_x

end program cfd_loop
