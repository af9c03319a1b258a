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
!>
!> Memory traffic, not arithmetic, sets the cost of a step (docs/performance.md, Fluid), so the
!> step is organised in as few sweeps as possible, plane by plane (momentum_terms):
!>   1. predictor sweep: E^n for u, v, w and u* in one pass; u* goes into the E^{n-1} arrays (no
!>      copy), and with explicit diffusion div u* / dt goes straight into the FFT buffer one plane
!>      behind (the plane just computed is still in cache);
!>   2. Poisson solve in the FFT buffer (no copies in or out);
!>   3. correction sweep: u^{n+1} = u* - dt grad phi in place in the u* arrays, phi read from the FFT
!>      buffer, the pressure, and the x-y halos; the arrays then rotate (u* -> u, E^n -> E^{n-1},
!>      u^n -> scratch; move_alloc, nothing copied) and one z-halo message per direction carries
!>      all three components.
!> The two single-plane halo messages (w* below, phi above) are in flight while interior planes
!> are computed.
module fluid_solver
  use agglo_kinds, only: wp, i8
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use halo_exchange, only: exchange_slab_halos, exchange_z_halos, start_plane_shift, finish_plane_shift
  use poisson_fft, only: poisson_fft_t, poisson_create, poisson_solve_in_buffer, helmholtz_solve
  use momentum_terms, only: predictor_coefficients_t, predictor_plane, divergence_plane, correction_plane
  use wall_clock, only: wall_time
  use timer_registry, only: timer_register, timer_add
  implicit none
  private
  public :: fluid_solver_t, fluid_solver_create, fluid_advance, fluid_exchange_velocity

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
                                                    !< (u* inside fluid_advance)
    logical :: has_history = .false.                !< E^{n-1} is valid (false before the first step)
    real(wp) :: dt_old = 0                          !< s, the previous step
    real(wp) :: time = 0                            !< s
    integer(i8) :: step = 0
    ! Work arrays, allocated once: E^n, div u* / dt for the Crank-Nicolson pressure (and callers'
    ! scratch), and the potential's plane above this slab (FFT padded layout).
    real(wp), allocatable :: explicit_u(:, :, :), explicit_v(:, :, :), explicit_w(:, :, :)
    real(wp), allocatable :: work(:, :, :)
    real(wp), allocatable :: phi_above(:, :)
    ! Handles of the solver's timers in the timer registry (core/timer_registry).
    integer :: timer_explicit = 0, timer_poisson = 0, timer_halo = 0
  end type fluid_solver_t

contains

  !> Grid, FFT plans and every array of the solver (collective), from the deck's &grid and &fluid
  !> (box, cells, viscosity, density, viscous_scheme, fft_planning). The velocity starts at rest.
  subroutine fluid_solver_create(solver, grid_cfg, fluid_cfg)
    type(fluid_solver_t), intent(inout) :: solver
    type(grid_config_t), intent(in) :: grid_cfg
    type(fluid_config_t), intent(in) :: fluid_cfg
    call grid_create(solver%grid, grid_cfg%nx, grid_cfg%ny, grid_cfg%nz, grid_cfg%length_x, grid_cfg%length_y, &
                     grid_cfg%length_z)
    call poisson_create(solver%poisson, solver%grid, trim(fluid_cfg%fft_planning))
    solver%viscosity = fluid_cfg%viscosity
    solver%density = fluid_cfg%density
    solver%crank_nicolson = (fluid_cfg%viscous_scheme == 'crank_nicolson')
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
    call allocate_field(solver%grid, solver%work)
    if (allocated(solver%phi_above)) deallocate(solver%phi_above)
    allocate(solver%phi_above(size(solver%poisson%real_view, 1), solver%grid%ny))
    solver%phi_above = 0
    solver%has_history = .false.
    solver%dt_old = 0; solver%time = 0; solver%step = 0
    solver%timer_explicit = timer_register('advection/diffusion')
    solver%timer_poisson = timer_register('Poisson/projection')
    solver%timer_halo = timer_register('halo exchange')
  end subroutine fluid_solver_create

  !> Refresh the halos of u, v, w (collective; one z message per direction), timed as halo exchange.
  subroutine fluid_exchange_velocity(solver)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp) :: t0
    t0 = wall_time()
    call exchange_slab_halos(solver%grid%slab, solver%u, solver%v, solver%w)
    call timer_add(solver%timer_halo, wall_time() - t0)
  end subroutine fluid_exchange_velocity

  !> One step of length dt (collective). Optional body force (m/s^2) on the faces, added with
  !> forward Euler (dt f^n, outside the multistep history). Velocity halos must be current on
  !> entry and are current on exit.
  subroutine fluid_advance(solver, dt, force_u, force_v, force_w)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    real(wp), intent(in), optional :: force_u(0:, 0:, 0:), force_v(0:, 0:, 0:), force_w(0:, 0:, 0:)
    type(predictor_coefficients_t) :: c
    real(wp) :: t0, t1, halo
    real(wp), allocatable :: swap(:, :, :)
    integer :: k, nzl

    t0 = wall_time()
    halo = 0
    nzl = solver%grid%nz_local
    c%dt = dt
    if (solver%has_history) then
      c%b1 = 1.0_wp + dt / (2.0_wp * solver%dt_old)
      c%b0 = -dt / (2.0_wp * solver%dt_old)
    else
      c%b1 = 1.0_wp
      c%b0 = 0.0_wp
    end if
    if (solver%crank_nicolson) then
      c%diffusion = 0.5_wp * solver%viscosity * dt
      c%explicit_weight = 0; c%implicit_weight = 1
    else
      c%diffusion = solver%viscosity
      c%explicit_weight = 1; c%implicit_weight = 0
    end if

    ! Predictor: explicit_old_* hold E^{n-1} on entry and u* after the sweep.
    if (solver%crank_nicolson) then
      do k = 1, nzl
        call predictor(k)
      end do
      ! (I - nu dt/2 L) u* = right-hand side, one FFT Helmholtz solve per component.
      call helmholtz_solve(solver%poisson, solver%explicit_old_u, c%diffusion)
      call helmholtz_solve(solver%poisson, solver%explicit_old_v, c%diffusion)
      call helmholtz_solve(solver%poisson, solver%explicit_old_w, c%diffusion)
      t1 = wall_time()
      call start_plane_shift(solver%grid%slab, solver%explicit_old_w(:, :, nzl), upward=.true.)
      call finish_plane_shift(solver%grid%slab, solver%explicit_old_w(:, :, 0), upward=.true.)
      halo = wall_time() - t1
      do k = 1, nzl
        call divergence_plane(solver%grid, k, solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w, &
                              1.0_wp / dt, solver%poisson%real_view)
      end do
      ! The CN pressure needs L phi = div u* / dt after the solve has overwritten the buffer.
      call keep_divergence()
    else
      ! The top plane first: its w* is the lower z halo of the slab above, in flight meanwhile.
      call predictor(nzl)
      call start_plane_shift(solver%grid%slab, solver%explicit_old_w(:, :, nzl), upward=.true.)
      do k = 1, nzl - 1
        call predictor(k)
        if (k > 1) call divergence_plane(solver%grid, k, solver%explicit_old_u, solver%explicit_old_v, &
                                         solver%explicit_old_w, 1.0_wp / dt, solver%poisson%real_view)
      end do
      if (nzl > 1) call divergence_plane(solver%grid, nzl, solver%explicit_old_u, solver%explicit_old_v, &
                                         solver%explicit_old_w, 1.0_wp / dt, solver%poisson%real_view)
      t1 = wall_time()
      call finish_plane_shift(solver%grid%slab, solver%explicit_old_w(:, :, 0), upward=.true.)
      halo = wall_time() - t1
      call divergence_plane(solver%grid, 1, solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w, &
                            1.0_wp / dt, solver%poisson%real_view)
    end if
    call timer_add(solver%timer_explicit, wall_time() - t0 - halo)
    call timer_add(solver%timer_halo, halo)

    call project(solver, dt)

    ! The corrected u* arrays become u^{n+1}, E^n becomes E^{n-1}, and u^n's arrays become next
    ! step's E^n scratch (moving the allocations: nothing is copied or allocated).
    call rotate(solver%u, solver%explicit_old_u, solver%explicit_u)
    call rotate(solver%v, solver%explicit_old_v, solver%explicit_v)
    call rotate(solver%w, solver%explicit_old_w, solver%explicit_w)
    ! correction_plane refreshed the x-y halos; the z halos of u, v, w go in one message each way.
    t1 = wall_time()
    call exchange_z_halos(solver%grid%slab, solver%u, solver%v, solver%w)
    call timer_add(solver%timer_halo, wall_time() - t1)
    solver%dt_old = dt
    solver%has_history = .true.
    solver%time = solver%time + dt
    solver%step = solver%step + 1

  contains

    !> work = div u* / dt (explicit loops: an array assignment from the FFT buffer's pointer
    !> could make the compiler allocate a temporary against aliasing).
    subroutine keep_divergence()
      integer :: i, j, k
      do k = 1, nzl
        do j = 1, solver%grid%ny
          do i = 1, solver%grid%nx
            solver%work(i, j, k) = solver%poisson%real_view(i, j, k)
          end do
        end do
      end do
    end subroutine keep_divergence

    !> velocity <- corrected (u^{n+1}), history <- explicit_now (E^n), explicit_now <- old velocity.
    subroutine rotate(velocity, history, explicit_now)
      real(wp), allocatable, intent(inout) :: velocity(:, :, :), history(:, :, :), explicit_now(:, :, :)
      call move_alloc(velocity, swap)
      call move_alloc(history, velocity)
      call move_alloc(explicit_now, history)
      call move_alloc(swap, explicit_now)
    end subroutine rotate

    subroutine predictor(k)
      integer, intent(in) :: k
      call predictor_plane(solver%grid, k, c, solver%u, solver%v, solver%w, &
                           solver%explicit_u, solver%explicit_v, solver%explicit_w, &
                           solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w, force_u, force_v, force_w)
    end subroutine predictor
  end subroutine fluid_advance

  !> Projection: the FFT buffer holds div u* / dt (interior) and explicit_old_* hold u*. Solve
  !> L phi = div u* / dt in the buffer, set u^{n+1} = u* - dt grad phi in place (with the x-y
  !> halos) and the pressure. The plane of phi above the slab travels while the other planes are
  !> corrected.
  subroutine project(solver, dt)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    real(wp) :: t0, t1, halo
    integer :: k, nzl
    nzl = solver%grid%nz_local
    t0 = wall_time()
    call poisson_solve_in_buffer(solver%poisson)
    ! phi's bottom plane is the top z halo of the slab below.
    t1 = wall_time()
    call start_plane_shift(solver%grid%slab, solver%poisson%real_view(:, :, 1), upward=.false.)
    halo = wall_time() - t1
    do k = 1, nzl - 1
      call correct(k, solver%poisson%real_view(:, :, k + 1))
    end do
    t1 = wall_time()
    call finish_plane_shift(solver%grid%slab, solver%phi_above, upward=.false.)
    halo = halo + wall_time() - t1
    call correct(nzl, solver%phi_above)
    call timer_add(solver%timer_poisson, wall_time() - t0 - halo)
    call timer_add(solver%timer_halo, halo)

  contains

    !> Velocity correction and pressure on plane k; phi_next is phi on plane k + 1.
    !> p^{n+1/2} = rho (phi - nu dt/2 L phi) (CN; L phi = div u* / dt is kept in work) or rho phi.
    subroutine correct(k, phi_next)
      integer, intent(in) :: k
      real(wp), intent(in), contiguous :: phi_next(:, :)
      integer :: i, j, nx
      nx = solver%grid%nx
      call correction_plane(solver%grid, k, solver%poisson%real_view(:, :, k), phi_next, dt, &
                            solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w)
      if (solver%crank_nicolson) then
        do j = 1, solver%grid%ny
          do i = 1, nx
            solver%pressure(i, j, k) = solver%density * (solver%poisson%real_view(i, j, k) &
                - 0.5_wp * solver%viscosity * dt * solver%work(i, j, k))
          end do
        end do
      else
        do j = 1, solver%grid%ny
          do i = 1, nx
            solver%pressure(i, j, k) = solver%density * solver%poisson%real_view(i, j, k)
          end do
        end do
      end if
    end subroutine correct
  end subroutine project
end module fluid_solver
