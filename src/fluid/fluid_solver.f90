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
!> Memory traffic, not arithmetic, sets the cost of a step (docs/studies/performance.md, Fluid), so the
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
!>
!> Incremental pressure (pressure_scheme = 'incremental', Brown, Cortez & Minion 2001, J. Comput.
!> Phys. 168, 464, the pressure-increment form with the Crank-Nicolson term): the predictor
!> carries the old gradient, u* = ... - (dt / rho) G p^{n-1/2}, and the pressure is updated,
!>   p^{n+1/2} = p^{n-1/2} + rho (phi - nu dt/2 L phi) (CN) or p^{n-1/2} + rho phi (explicit).
!> In the periodic box without bodies the projection removes any gradient exactly, so both schemes
!> give the same u and p (to round-off). With immersed bodies they differ: the incremental one sets
!> the ghost values on a u* that already holds the pressure gradient (no dt-dependent slip; the
!> prescribed-motion validation uses it), but two flat faces within about a cell of each other grow
!> without bound with it (docs/theory.md, "Known limit: disks face to face within about a cell").
!> The resolved pair decks therefore keep the pressure-free default: stable there, with a splitting
!> error that lowers the squeeze force near contact (it decreases with dt), which the sub-grid
!> lubrication's larger hand-over for this scheme absorbs (config_collision,
!> default_lubrication_handover; docs/studies/validation.md, "Lubrication").
!>
!> The staged step (docs/design.md, the step's stages) is the same step cut where the immersed
!> boundary must act; a driver calls, in this order,
!>   fluid_predict(solver, dt [, predictor] [, force_u, force_v, force_w])
!>       u* complete in explicit_old_u|v|w with every halo current; predictor (a class extending
!>       predictor_solver_t) solves A u* = b, default the FFT (predictor_solver);
!>   [the coupling sets ghost and interior values of u*, then refreshes the halos]
!>   fluid_project(solver)
!>       div u*, Poisson solve, u^{n+1} = u* - dt G phi in u, v, w (every halo current), pressure
!>       p^{n+1/2} (every halo current);
!>   [the coupling re-imposes ghost and interior values of u^{n+1}, then fluid_exchange_velocity]
!>   fluid_finish_step(solver)
!>       the history rotates (E^n -> E^{n-1}), time and step advance.
!> With the default predictor solver and nothing done between the stages, the staged step gives
!> fluid_advance's result to round-off; fluid_advance (the fused sweep) stays the path of the
!> particle-free scene. The pressure keeps current halos after either path.
module fluid_solver
  use agglo_kinds, only: wp, i8
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use halo_exchange, only: exchange_slab_halos, exchange_z_halos, start_plane_shift, finish_plane_shift
  use poisson_fft, only: poisson_fft_t, poisson_create, poisson_solve_in_buffer
  use momentum_terms, only: predictor_coefficients_t, predictor_plane, divergence_plane, correction_plane
  use predictor_solver, only: predictor_solver_t, fft_predictor_solver_t
  use error_handling, only: fatal
  use wall_clock, only: wall_time
  use timer_registry, only: timer_register, timer_add
  implicit none
  private
  public :: fluid_solver_t, fluid_solver_create, fluid_advance, fluid_exchange_velocity, &
            fluid_predict, fluid_project, fluid_finish_step, fluid_select_pressure_scheme

  !> Where a staged step stands (fluid_solver_t%stage): the stages must come in order.
  integer, parameter :: stage_idle = 0, stage_predicted = 1, stage_projected = 2
  !> The FFT solve of the predictor (holds no data: one instance serves every solver).
  type(fft_predictor_solver_t) :: default_predictor

  type :: fluid_solver_t
    type(fluid_grid_t) :: grid
    type(poisson_fft_t) :: poisson
    real(wp) :: viscosity = 0                       !< m^2/s, kinematic
    real(wp) :: density = 1                         !< kg/m^3 (pressure is stored in Pa)
    logical :: crank_nicolson = .false.
    ! State (what a checkpoint must hold for a bit-for-bit continuation).
    real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :)   !< m/s, face velocities, halos current
    real(wp), allocatable :: pressure(:, :, :)      !< Pa at the cell centres, time n - 1/2 (halos current
                                                    !< after a step)
    real(wp), allocatable :: explicit_old_u(:, :, :), explicit_old_v(:, :, :), explicit_old_w(:, :, :)  !< E^{n-1}
                                                    !< (u* inside fluid_advance and between fluid_predict
                                                    !< and fluid_project)
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
    ! Pressure scheme (fluid_select_pressure_scheme) and the staged step in progress.
    logical :: incremental_pressure = .false.       !< the predictor carries - (dt / rho) G p^{n-1/2}
    integer :: stage = stage_idle
    type(predictor_coefficients_t) :: stage_coefficients   !< of the staged step in progress
  end type fluid_solver_t

contains

  !> Grid, FFT plans and every array of the solver (collective), from the deck's &grid and &fluid
  !> (box, cells, viscosity, density, viscous_scheme, fft_planning, pressure_scheme). The velocity
  !> starts at rest.
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
    call fluid_select_pressure_scheme(solver, trim(fluid_cfg%pressure_scheme))
  end subroutine fluid_solver_create

  !> Refresh the halos of u, v, w (collective; one z message per direction), timed as halo exchange.
  subroutine fluid_exchange_velocity(solver)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp) :: t0
    t0 = wall_time()
    call exchange_slab_halos(solver%grid%slab, solver%u, solver%v, solver%w)
    call timer_add(solver%timer_halo, wall_time() - t0)
  end subroutine fluid_exchange_velocity

  !> 'non_incremental' (the pressure-free projection, the default) or 'incremental' (the old pressure
  !> gradient in the predictor; module header). Any other name is a programming error: the deck
  !> check (&fluid pressure_scheme) has refused it before.
  subroutine fluid_select_pressure_scheme(solver, scheme)
    type(fluid_solver_t), intent(inout) :: solver
    character(len=*), intent(in) :: scheme
    select case (scheme)
    case ('non_incremental'); solver%incremental_pressure = .false.
    case ('incremental'); solver%incremental_pressure = .true.
    case default; call fatal('fluid_select_pressure_scheme: unknown pressure scheme '''//trim(scheme)//'''')
    end select
  end subroutine fluid_select_pressure_scheme

  !> One step of length dt (collective), the fused sweep. Optional body force (m/s^2) on the faces,
  !> added with forward Euler (dt f^n, outside the multistep history). Velocity halos must be
  !> current on entry and are current on exit.
  subroutine fluid_advance(solver, dt, force_u, force_v, force_w)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    real(wp), intent(in), optional :: force_u(0:, 0:, 0:), force_v(0:, 0:, 0:), force_w(0:, 0:, 0:)
    type(predictor_coefficients_t) :: c
    real(wp) :: t0, t1, halo
    integer :: k, nzl

    if (solver%stage /= stage_idle) call fatal('fluid_advance: called inside a staged step', collective=.false.)
    t0 = wall_time()
    nzl = solver%grid%nz_local
    c = step_coefficients(solver, dt)
    halo = refresh_pressure_halos(solver)

    ! Predictor: explicit_old_* hold E^{n-1} on entry and u* after the sweep.
    if (solver%crank_nicolson) then
      do k = 1, nzl
        call predictor_sweep_plane(solver, k, c, force_u, force_v, force_w)
      end do
      ! (I - nu dt/2 L) u* = right-hand side, one FFT Helmholtz solve per component.
      call default_predictor%solve(solver%grid, solver%poisson, c%diffusion, solver%explicit_old_u, &
                                   solver%explicit_old_v, solver%explicit_old_w)
      t1 = wall_time()
      call start_plane_shift(solver%grid%slab, solver%explicit_old_w(:, :, nzl), upward=.true.)
      call finish_plane_shift(solver%grid%slab, solver%explicit_old_w(:, :, 0), upward=.true.)
      halo = halo + wall_time() - t1
      call divergence_sweep(solver, dt)
      ! The CN pressure needs L phi = div u* / dt after the solve has overwritten the buffer.
      call keep_divergence(solver)
    else
      ! The top plane first: its w* is the lower z halo of the slab above, in flight meanwhile.
      call predictor_sweep_plane(solver, nzl, c, force_u, force_v, force_w)
      call start_plane_shift(solver%grid%slab, solver%explicit_old_w(:, :, nzl), upward=.true.)
      do k = 1, nzl - 1
        call predictor_sweep_plane(solver, k, c, force_u, force_v, force_w)
        if (k > 1) call divergence_plane(solver%grid, k, solver%explicit_old_u, solver%explicit_old_v, &
                                         solver%explicit_old_w, 1.0_wp / dt, solver%poisson%real_view)
      end do
      if (nzl > 1) call divergence_plane(solver%grid, nzl, solver%explicit_old_u, solver%explicit_old_v, &
                                         solver%explicit_old_w, 1.0_wp / dt, solver%poisson%real_view)
      t1 = wall_time()
      call finish_plane_shift(solver%grid%slab, solver%explicit_old_w(:, :, 0), upward=.true.)
      halo = halo + wall_time() - t1
      call divergence_plane(solver%grid, 1, solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w, &
                            1.0_wp / dt, solver%poisson%real_view)
    end if
    call timer_add(solver%timer_explicit, wall_time() - t0 - halo)
    call timer_add(solver%timer_halo, halo)

    call project(solver, dt)
    call accept_corrected_velocity(solver)
    call rotate_history(solver, dt)
  end subroutine fluid_advance

  !> Stage 1 of the staged step (collective): the momentum predictor. On exit explicit_old_u|v|w
  !> hold u* (every halo current) and explicit_u|v|w hold E^n. predictor solves A u* = b
  !> (predictor_solver); without it the FFT solves it. Body force and halos as for fluid_advance.
  subroutine fluid_predict(solver, dt, predictor, force_u, force_v, force_w)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    class(predictor_solver_t), intent(inout), optional :: predictor
    real(wp), intent(in), optional :: force_u(0:, 0:, 0:), force_v(0:, 0:, 0:), force_w(0:, 0:, 0:)
    type(predictor_coefficients_t) :: c
    real(wp) :: t0, t1, halo, alpha
    integer :: k

    if (solver%stage /= stage_idle) call fatal('fluid_predict: the previous staged step is not finished', &
                                               collective=.false.)
    t0 = wall_time()
    c = step_coefficients(solver, dt)
    halo = refresh_pressure_halos(solver)
    do k = 1, solver%grid%nz_local
      call predictor_sweep_plane(solver, k, c, force_u, force_v, force_w)
    end do
    alpha = 0
    if (solver%crank_nicolson) alpha = c%diffusion
    if (present(predictor)) then
      call predictor%solve(solver%grid, solver%poisson, alpha, solver%explicit_old_u, solver%explicit_old_v, &
                           solver%explicit_old_w)
    else
      call default_predictor%solve(solver%grid, solver%poisson, alpha, solver%explicit_old_u, &
                                   solver%explicit_old_v, solver%explicit_old_w)
    end if
    t1 = wall_time()
    call exchange_slab_halos(solver%grid%slab, solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w)
    halo = halo + wall_time() - t1
    call timer_add(solver%timer_explicit, wall_time() - t0 - halo)
    call timer_add(solver%timer_halo, halo)
    solver%stage_coefficients = c
    solver%stage = stage_predicted
  end subroutine fluid_predict

  !> Stage 2 (collective): the projection of u* (explicit_old_u|v|w, every halo current, as
  !> fluid_predict left them or the coupling changed them). On exit u, v, w hold u^{n+1} and the
  !> pressure p^{n+1/2}, every halo current.
  subroutine fluid_project(solver)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp) :: t0, dt
    if (solver%stage /= stage_predicted) call fatal('fluid_project: fluid_predict has not been called', &
                                                    collective=.false.)
    dt = solver%stage_coefficients%dt
    t0 = wall_time()
    call divergence_sweep(solver, dt)
    if (solver%crank_nicolson) call keep_divergence(solver)
    call timer_add(solver%timer_explicit, wall_time() - t0)
    call project(solver, dt)
    call accept_corrected_velocity(solver)
    solver%stage = stage_projected
  end subroutine fluid_project

  !> Stage 3: the multistep history rotates (E^n becomes E^{n-1}), time and step advance. Velocity
  !> halos must be current (a caller that changed u, v, w after fluid_project has refreshed them).
  subroutine fluid_finish_step(solver)
    type(fluid_solver_t), intent(inout) :: solver
    if (solver%stage /= stage_projected) call fatal('fluid_finish_step: fluid_project has not been called', &
                                                    collective=.false.)
    call rotate_history(solver, solver%stage_coefficients%dt)
    solver%stage = stage_idle
  end subroutine fluid_finish_step

  !> The predictor's coefficients for a step of length dt (AB2 with the variable-step weights, or
  !> forward Euler on the first step; the viscous term explicit or Crank-Nicolson).
  type(predictor_coefficients_t) function step_coefficients(solver, dt) result(c)
    type(fluid_solver_t), intent(in) :: solver
    real(wp), intent(in) :: dt
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
    c%pressure_factor = dt / solver%density
  end function step_coefficients

  !> With the incremental pressure, refresh the halos of p^{n-1/2} (they are current after a step,
  !> but not necessarily after an initial field or a checkpoint was read). Returns the time taken.
  real(wp) function refresh_pressure_halos(solver) result(seconds)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp) :: t0
    seconds = 0
    if (.not. solver%incremental_pressure) return
    t0 = wall_time()
    call exchange_slab_halos(solver%grid%slab, solver%pressure)
    seconds = wall_time() - t0
  end function refresh_pressure_halos

  !> Plane k of the predictor sweep (momentum_terms%predictor_plane on the solver's arrays, with
  !> the old pressure gradient when the scheme is incremental).
  subroutine predictor_sweep_plane(solver, k, c, force_u, force_v, force_w)
    type(fluid_solver_t), intent(inout) :: solver
    integer, intent(in) :: k
    type(predictor_coefficients_t), intent(in) :: c
    real(wp), intent(in), optional :: force_u(0:, 0:, 0:), force_v(0:, 0:, 0:), force_w(0:, 0:, 0:)
    if (solver%incremental_pressure) then
      call predictor_plane(solver%grid, k, c, solver%u, solver%v, solver%w, &
                           solver%explicit_u, solver%explicit_v, solver%explicit_w, &
                           solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w, force_u, force_v, force_w, &
                           solver%pressure)
    else
      call predictor_plane(solver%grid, k, c, solver%u, solver%v, solver%w, &
                           solver%explicit_u, solver%explicit_v, solver%explicit_w, &
                           solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w, force_u, force_v, force_w)
    end if
  end subroutine predictor_sweep_plane

  !> FFT buffer = div u* / dt on every plane; u* (explicit_old_*) needs w*'s lower z halo current.
  subroutine divergence_sweep(solver, dt)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    integer :: k
    do k = 1, solver%grid%nz_local
      call divergence_plane(solver%grid, k, solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w, &
                            1.0_wp / dt, solver%poisson%real_view)
    end do
  end subroutine divergence_sweep

  !> work = div u* / dt (explicit loops: an array assignment from the FFT buffer's pointer
  !> could make the compiler allocate a temporary against aliasing).
  subroutine keep_divergence(solver)
    type(fluid_solver_t), intent(inout) :: solver
    integer :: i, j, k
    do k = 1, solver%grid%nz_local
      do j = 1, solver%grid%ny
        do i = 1, solver%grid%nx
          solver%work(i, j, k) = solver%poisson%real_view(i, j, k)
        end do
      end do
    end do
  end subroutine keep_divergence

  !> After the correction: the corrected u* arrays become u, v, w (u^n's arrays take their place
  !> until rotate_history; moving the allocations copies nothing). correction_plane refreshed the
  !> x-y halos; the z halos of u, v, w go in one message each way.
  subroutine accept_corrected_velocity(solver)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp) :: t1
    call swap(solver%u, solver%explicit_old_u)
    call swap(solver%v, solver%explicit_old_v)
    call swap(solver%w, solver%explicit_old_w)
    t1 = wall_time()
    call exchange_z_halos(solver%grid%slab, solver%u, solver%v, solver%w)
    call timer_add(solver%timer_halo, wall_time() - t1)
  end subroutine accept_corrected_velocity

  !> E^n becomes E^{n-1} and u^n's arrays become next step's E^n scratch; the clock advances.
  subroutine rotate_history(solver, dt)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    call swap(solver%explicit_old_u, solver%explicit_u)
    call swap(solver%explicit_old_v, solver%explicit_v)
    call swap(solver%explicit_old_w, solver%explicit_w)
    solver%dt_old = dt
    solver%has_history = .true.
    solver%time = solver%time + dt
    solver%step = solver%step + 1
  end subroutine rotate_history

  !> Exchange two allocations (move_alloc: nothing copied, nothing allocated).
  subroutine swap(a, b)
    real(wp), allocatable, intent(inout) :: a(:, :, :), b(:, :, :)
    real(wp), allocatable :: held(:, :, :)
    call move_alloc(a, held)
    call move_alloc(b, a)
    call move_alloc(held, b)
  end subroutine swap

  !> Projection: the FFT buffer holds div u* / dt (interior) and explicit_old_* hold u*. Solve
  !> L phi = div u* / dt in the buffer, set u^{n+1} = u* - dt grad phi in place (with the x-y
  !> halos) and the pressure (with its halos). The plane of phi above the slab travels while the
  !> other planes are corrected.
  subroutine project(solver, dt)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    real(wp) :: t0, t1, halo, kept
    integer :: k, nzl
    nzl = solver%grid%nz_local
    ! p^{n+1/2} = kept p^{n-1/2} + rho (...): kept = 1 (incremental) or 0 (0 p + x is x exactly).
    kept = merge(1.0_wp, 0.0_wp, solver%incremental_pressure)
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
    t1 = wall_time()
    call exchange_z_halos(solver%grid%slab, solver%pressure)
    halo = halo + wall_time() - t1
    call timer_add(solver%timer_poisson, wall_time() - t0 - halo)
    call timer_add(solver%timer_halo, halo)

  contains

    !> Velocity correction and pressure on plane k; phi_next is phi on plane k + 1.
    !> p^{n+1/2} = kept p^{n-1/2} + rho (phi - nu dt/2 L phi) (CN; L phi = div u* / dt is kept in
    !> work) or kept p^{n-1/2} + rho phi, then the plane's x-y halo ring (row by row, cache-hot).
    subroutine correct(k, phi_next)
      integer, intent(in) :: k
      real(wp), intent(in), contiguous :: phi_next(:, :)
      integer :: i, j, nx, ny
      nx = solver%grid%nx; ny = solver%grid%ny
      call correction_plane(solver%grid, k, solver%poisson%real_view(:, :, k), phi_next, dt, &
                            solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w)
      do j = 1, ny
        if (solver%crank_nicolson) then
          do i = 1, nx
            solver%pressure(i, j, k) = kept * solver%pressure(i, j, k) + solver%density * &
                (solver%poisson%real_view(i, j, k) - 0.5_wp * solver%viscosity * dt * solver%work(i, j, k))
          end do
        else
          do i = 1, nx
            solver%pressure(i, j, k) = kept * solver%pressure(i, j, k) + solver%density * solver%poisson%real_view(i, j, k)
          end do
        end if
        solver%pressure(0, j, k) = solver%pressure(nx, j, k); solver%pressure(nx + 1, j, k) = solver%pressure(1, j, k)
      end do
      do i = 0, nx + 1
        solver%pressure(i, 0, k) = solver%pressure(i, ny, k); solver%pressure(i, ny + 1, k) = solver%pressure(i, 1, k)
      end do
    end subroutine correct
  end subroutine project
end module fluid_solver
