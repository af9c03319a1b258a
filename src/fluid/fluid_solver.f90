!> The incompressible Navier-Stokes solver of the periodic box: state, work arrays and one time step.
!>
!> Time integration (docs/theory.md, fluid section): second-order Adams-Bashforth for the explicit
!> terms E = -N(u) [+ nu L u when viscous_scheme = 'explicit'] with the variable-step coefficients
!> b1 = 1 + dt/(2 dt_old), b0 = -dt/(2 dt_old) (forward Euler on the first step), Crank-Nicolson
!> for nu L u when viscous_scheme = 'crank_nicolson' (solved with the FFT, the operator being
!> constant-coefficient and periodic), then a pressure-free projection:
!>   u* = u^n + dt (b1 E^n + b0 E^{n-1} + f) [+ nu dt/2 L(u^n + u*)]
!>   L phi = div u* / dt,   u^{n+1} = u* - dt grad phi,
!>   p^{n+1/2} = rho (phi - nu dt/2 L phi) (CN) or rho phi (explicit)  (Brown, Cortez & Minion 2001).
!> In a periodic box the discrete projection commutes with L and (I - nu dt/2 L), so this is the
!> second-order AB2/CN scheme applied to the projected equations; u^{n+1} is solenoidal to round-off.
!> Restartable history: E^{n-1}, dt_old and has_history (see fluid_solver_t).
module fluid_solver
  use agglo_kinds, only: wp, i8
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field, exchange_halos
  use poisson_fft, only: poisson_fft_t, poisson_create, poisson_solve, helmholtz_solve
  use momentum_terms, only: explicit_terms, laplacian, divergence, subtract_gradient
  use wall_clock, only: wall_time
  implicit none
  private
  public :: fluid_solver_t, fluid_solver_create, fluid_advance, fluid_exchange_velocity, &
            timer_names, timer_count, timer_explicit, timer_poisson, timer_halo, timer_io

  integer, parameter :: timer_count = 4
  integer, parameter :: timer_explicit = 1, timer_poisson = 2, timer_halo = 3, timer_io = 4
  character(len=24), parameter :: timer_names(timer_count) = [character(len=24) :: &
      'advection/diffusion', 'Poisson/projection', 'halo exchange', 'I/O']

  type :: fluid_solver_t
    type(fluid_grid_t) :: grid
    type(poisson_fft_t) :: poisson
    real(wp) :: viscosity = 0                       !< m^2/s, kinematic
    real(wp) :: density = 1                         !< kg/m^3 (pressure is stored in Pa)
    logical :: crank_nicolson = .false.
    ! State (what a checkpoint must hold for a bit-for-bit continuation).
    real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :)   !< m/s, face velocities, halos current
    real(wp), allocatable :: pressure(:, :, :)      !< Pa at the cell centres, time n - 1/2 (interior only)
    real(wp), allocatable :: explicit_old_u(:, :, :), explicit_old_v(:, :, :), explicit_old_w(:, :, :)  !< E^{n-1}
    logical :: has_history = .false.                !< E^{n-1} is valid (false before the first step)
    real(wp) :: dt_old = 0                          !< s, the previous step
    real(wp) :: time = 0                            !< s
    integer(i8) :: step = 0
    ! Work arrays, allocated once.
    real(wp), allocatable :: explicit_u(:, :, :), explicit_v(:, :, :), explicit_w(:, :, :)
    real(wp), allocatable :: phi(:, :, :), work(:, :, :)
    real(wp) :: timers(timer_count) = 0             !< s accumulated per category on this rank
  end type fluid_solver_t

contains

  !> Grid, FFT plans and every array of the solver (collective). The velocity starts at rest.
  subroutine fluid_solver_create(solver, nx, ny, nz, lx, ly, lz, viscosity, density, viscous_scheme, &
                                 fft_planning)
    type(fluid_solver_t), intent(inout) :: solver
    integer, intent(in) :: nx, ny, nz
    real(wp), intent(in) :: lx, ly, lz, viscosity, density
    character(len=*), intent(in) :: viscous_scheme, fft_planning
    call grid_create(solver%grid, nx, ny, nz, lx, ly, lz)
    call poisson_create(solver%poisson, solver%grid, fft_planning)
    solver%viscosity = viscosity
    solver%density = density
    solver%crank_nicolson = (viscous_scheme == 'crank_nicolson')
    call allocate_field(solver%grid, solver%u)
    call allocate_field(solver%grid, solver%v)
    call allocate_field(solver%grid, solver%w)
    call allocate_field(solver%grid, solver%pressure)
    call allocate_field(solver%grid, solver%explicit_old_u)
    call allocate_field(solver%grid, solver%explicit_old_v)
    call allocate_field(solver%grid, solver%explicit_old_w)
    call allocate_field(solver%grid, solver%explicit_u)
    call allocate_field(solver%grid, solver%explicit_v)
    call allocate_field(solver%grid, solver%explicit_w)
    call allocate_field(solver%grid, solver%phi)
    call allocate_field(solver%grid, solver%work)
    solver%has_history = .false.
    solver%dt_old = 0; solver%time = 0; solver%step = 0
    solver%timers = 0
  end subroutine fluid_solver_create

  !> Refresh the halos of u, v, w (collective), timed as halo exchange.
  subroutine fluid_exchange_velocity(solver)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp) :: t0
    t0 = wall_time()
    call exchange_halos(solver%grid, solver%u)
    call exchange_halos(solver%grid, solver%v)
    call exchange_halos(solver%grid, solver%w)
    solver%timers(timer_halo) = solver%timers(timer_halo) + wall_time() - t0
  end subroutine fluid_exchange_velocity

  !> One step of length dt (collective). Optional body force (m/s^2) on the faces, added with
  !> forward Euler (dt f^n, outside the multistep history). Velocity halos must be current on
  !> entry and are current on exit.
  subroutine fluid_advance(solver, dt, force_u, force_v, force_w)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    real(wp), intent(in), optional :: force_u(0:, 0:, 0:), force_v(0:, 0:, 0:), force_w(0:, 0:, 0:)
    real(wp) :: b1, b0, half_nu_dt, t0, t1
    real(wp), allocatable :: swap(:, :, :)

    t0 = wall_time()
    if (solver%has_history) then
      b1 = 1.0_wp + dt / (2.0_wp * solver%dt_old)
      b0 = -dt / (2.0_wp * solver%dt_old)
    else
      b1 = 1.0_wp
      b0 = 0.0_wp
    end if
    half_nu_dt = 0.5_wp * solver%viscosity * dt
    call explicit_terms(solver%grid, solver%u, solver%v, solver%w, &
                        merge(0.0_wp, solver%viscosity, solver%crank_nicolson), &
                        solver%explicit_u, solver%explicit_v, solver%explicit_w)
    call predict(solver%u, solver%explicit_u, solver%explicit_old_u, force_u)
    call predict(solver%v, solver%explicit_v, solver%explicit_old_v, force_v)
    call predict(solver%w, solver%explicit_w, solver%explicit_old_w, force_w)
    ! E^n becomes E^{n-1} (swapping the allocations: nothing is copied or allocated).
    call move_alloc(solver%explicit_old_u, swap); call move_alloc(solver%explicit_u, solver%explicit_old_u)
    call move_alloc(swap, solver%explicit_u)
    call move_alloc(solver%explicit_old_v, swap); call move_alloc(solver%explicit_v, solver%explicit_old_v)
    call move_alloc(swap, solver%explicit_v)
    call move_alloc(solver%explicit_old_w, swap); call move_alloc(solver%explicit_w, solver%explicit_old_w)
    call move_alloc(swap, solver%explicit_w)
    t1 = wall_time()
    solver%timers(timer_explicit) = solver%timers(timer_explicit) + t1 - t0

    call fluid_exchange_velocity(solver)
    call project(solver, dt)
    call fluid_exchange_velocity(solver)
    solver%dt_old = dt
    solver%has_history = .true.
    solver%time = solver%time + dt
    solver%step = solver%step + 1

  contains

    !> u <- u* (interior); the Crank-Nicolson form needs u's halos for L u^n, current on entry.
    subroutine predict(vel, explicit_now, explicit_old, force)
      real(wp), intent(inout) :: vel(0:, 0:, 0:)
      real(wp), intent(in) :: explicit_now(0:, 0:, 0:), explicit_old(0:, 0:, 0:)
      real(wp), intent(in), optional :: force(0:, 0:, 0:)
      integer :: i, j, k, nx, ny, nzl
      nx = solver%grid%nx; ny = solver%grid%ny; nzl = solver%grid%nz_local
      if (solver%crank_nicolson) then
        call laplacian(solver%grid, vel, solver%work)
        do k = 1, nzl
          do j = 1, ny
            do i = 1, nx
              solver%work(i, j, k) = vel(i, j, k) + dt * (b1 * explicit_now(i, j, k) + b0 * explicit_old(i, j, k)) &
                                   + half_nu_dt * solver%work(i, j, k)
            end do
          end do
        end do
        if (present(force)) solver%work(1:nx, 1:ny, 1:nzl) = solver%work(1:nx, 1:ny, 1:nzl) + dt * force(1:nx, 1:ny, 1:nzl)
        call helmholtz_solve(solver%poisson, solver%work, half_nu_dt)
        vel(1:nx, 1:ny, 1:nzl) = solver%work(1:nx, 1:ny, 1:nzl)
      else
        do k = 1, nzl
          do j = 1, ny
            do i = 1, nx
              vel(i, j, k) = vel(i, j, k) + dt * (b1 * explicit_now(i, j, k) + b0 * explicit_old(i, j, k))
            end do
          end do
        end do
        if (present(force)) vel(1:nx, 1:ny, 1:nzl) = vel(1:nx, 1:ny, 1:nzl) + dt * force(1:nx, 1:ny, 1:nzl)
      end if
    end subroutine predict
  end subroutine fluid_advance

  !> Projection of the predicted velocity (halos current): solve L phi = div u* / dt, correct the
  !> velocity (interior) and set the pressure. Velocity halos are stale on exit.
  subroutine project(solver, dt)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    real(wp) :: t0, t1
    integer :: nx, ny, nzl
    nx = solver%grid%nx; ny = solver%grid%ny; nzl = solver%grid%nz_local
    t0 = wall_time()
    call divergence(solver%grid, solver%u, solver%v, solver%w, 1.0_wp / dt, solver%work)
    call poisson_solve(solver%poisson, solver%work, solver%phi)
    t1 = wall_time()
    call exchange_halos(solver%grid, solver%phi)
    solver%timers(timer_halo) = solver%timers(timer_halo) + wall_time() - t1
    t1 = wall_time()
    call subtract_gradient(solver%grid, solver%phi, dt, solver%u, solver%v, solver%w)
    ! work = L phi = div u* / dt, so the CN pressure needs no extra stencil.
    if (solver%crank_nicolson) then
      solver%pressure(1:nx, 1:ny, 1:nzl) = solver%density * (solver%phi(1:nx, 1:ny, 1:nzl) &
          - 0.5_wp * solver%viscosity * dt * solver%work(1:nx, 1:ny, 1:nzl))
    else
      solver%pressure(1:nx, 1:ny, 1:nzl) = solver%density * solver%phi(1:nx, 1:ny, 1:nzl)
    end if
    solver%timers(timer_poisson) = solver%timers(timer_poisson) + wall_time() - t1 + (t1 - t0)
  end subroutine project
end module fluid_solver
