!> Checks of the staged fluid step shared by the 1-rank and 2-rank test programs
!> (test_fluid_stages, test_fluid_stages_two_ranks):
!> - the staged step with the default (FFT) predictor solve reproduces the fused fluid_advance to
!>   round-off, explicit and Crank-Nicolson, with a body force and a changing dt (the same
!>   operations in another order of sweeps: only round-off may differ);
!> - a caller's own predictor solver (Jacobi iterations on A = I - alpha L built from
!>   apply_predictor_operator, as a coupling room would write one) gives the FFT solve's step;
!> - the incremental pressure scheme gives the non-incremental velocity and pressure to round-off
!>   in the periodic box (the discrete projection removes the gradient of any cell-centred field
!>   exactly, docs/theory.md; Brown, Cortez & Minion 2001 for the pressure update).
module fluid_stage_checks
  use agglo_kinds, only: wp, i8
  use physical_constants, only: two_pi
  use parallel_env, only: global_max
  use random_stream, only: random_stream_t, stream_seed, stream_normal
  use fluid_grid, only: fluid_grid_t, allocate_field, exchange_halos
  use poisson_fft, only: poisson_fft_t
  use predictor_solver, only: predictor_solver_t, apply_predictor_operator
  use fluid_solver, only: fluid_solver_t, fluid_solver_create, fluid_advance, fluid_predict, fluid_project, &
                          fluid_finish_step
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use initial_fields, only: set_random_field
  use test_framework, only: check_below, check_equal
  implicit none
  private
  public :: run_fluid_stage_checks

  !> A predictor solver as another room would write it: Jacobi iterations x <- x + (b - A x) / diag(A)
  !> until the largest update is below tolerance (A is diagonally dominant, so they converge).
  type, extends(predictor_solver_t) :: jacobi_predictor_solver_t
    real(wp) :: tolerance = 1.0e-15_wp      !< on max |update| / max |b|
    integer :: calls = 0, iterations = 0
    real(wp), allocatable :: rhs(:, :, :), residual(:, :, :)
  contains
    procedure :: solve => jacobi_solve
  end type jacobi_predictor_solver_t

contains

  subroutine run_fluid_stage_checks(suffix)
    character(len=*), intent(in) :: suffix    !< appended to the check names (rank count)
    character(len=16) :: scheme
    integer :: n
    do n = 1, 2
      scheme = merge('explicit      ', 'crank_nicolson', n == 1)
      call check_staged_matches_fused(trim(scheme), 'non_incremental', suffix)
      call check_staged_matches_fused(trim(scheme), 'incremental', suffix)
      call check_incremental_matches_non_incremental(trim(scheme), suffix)
    end do
    call check_own_predictor_solver(suffix)
  end subroutine run_fluid_stage_checks

  !> A random field in a 1 x 0.5 x 0.25 box (32 x 16 x 8 cells; on 2 ranks 4 planes each), viscosity
  !> 0.02 (nu dt / dx^2 about 0.02), and a random body force.
  subroutine make_case(solver, viscous_scheme, pressure_scheme, force_u, force_v, force_w)
    type(fluid_solver_t), intent(inout) :: solver
    character(len=*), intent(in) :: viscous_scheme, pressure_scheme
    real(wp), allocatable, intent(inout) :: force_u(:, :, :), force_v(:, :, :), force_w(:, :, :)
    type(random_stream_t) :: stream
    integer :: i, j, k
    call fluid_solver_create(solver, grid_config_t(nx=32, ny=16, nz=8, length_x=1.0_wp, length_y=0.5_wp, length_z=0.25_wp), &
                             fluid_config_t(viscosity=2.0e-2_wp, density=1000.0_wp, viscous_scheme=viscous_scheme, &
                                            fft_planning='estimate', pressure_scheme=pressure_scheme))
    call set_random_field(solver, 11_i8, 1.0_wp, two_pi * 2.0_wp)
    call allocate_field(solver%grid, force_u); call allocate_field(solver%grid, force_v)
    call allocate_field(solver%grid, force_w)
    call stream_seed(stream, 7_i8)
    do k = 1, solver%grid%nz_local
      do j = 1, solver%grid%ny
        do i = 1, solver%grid%nx
          force_u(i, j, k) = stream_normal(stream); force_v(i, j, k) = stream_normal(stream)
          force_w(i, j, k) = stream_normal(stream)
        end do
      end do
    end do
  end subroutine make_case

  !> dt of step s: varies, so the variable-step AB2 weights are exercised.
  pure real(wp) function step_dt(s)
    integer, intent(in) :: s
    step_dt = 1.0e-3_wp * (1.0_wp + 0.1_wp * mod(s, 3))
  end function step_dt

  !> max over the slab's interiors and ranks of |a - b|, relative to max |b| of the velocity.
  real(wp) function field_difference(a, b, grid) result(difference)
    real(wp), intent(in) :: a(0:, 0:, 0:), b(0:, 0:, 0:)
    type(fluid_grid_t), intent(in) :: grid
    integer :: nx, ny, nz
    nx = grid%nx; ny = grid%ny; nz = grid%nz_local
    difference = global_max(maxval(abs(a(1:nx, 1:ny, 1:nz) - b(1:nx, 1:ny, 1:nz)))) &
               / max(global_max(maxval(abs(b(1:nx, 1:ny, 1:nz)))), tiny(1.0_wp))
  end function field_difference

  !> Also the halo layers: the staged path promises every halo current, like the fused one.
  real(wp) function full_difference(a, b) result(difference)
    real(wp), intent(in) :: a(0:, 0:, 0:), b(0:, 0:, 0:)
    difference = global_max(maxval(abs(a - b))) / max(global_max(maxval(abs(b))), tiny(1.0_wp))
  end function full_difference

  !> 6 steps fused against 6 staged steps: velocity, pressure (with halos) and the AB2 history
  !> agree to round-off (1e-13 relative: the same arithmetic, so the only difference allowed is
  !> the order of a few floating-point operations).
  subroutine check_staged_matches_fused(viscous_scheme, pressure_scheme, suffix)
    character(len=*), intent(in) :: viscous_scheme, pressure_scheme, suffix
    type(fluid_solver_t) :: fused, staged
    real(wp), allocatable :: fu(:, :, :), fv(:, :, :), fw(:, :, :), halo_check(:, :, :)
    real(wp) :: velocity, pressure, history
    integer :: s
    call make_case(fused, viscous_scheme, pressure_scheme, fu, fv, fw)
    call make_case(staged, viscous_scheme, pressure_scheme, fu, fv, fw)
    do s = 1, 6
      call fluid_advance(fused, step_dt(s), fu, fv, fw)
      call fluid_predict(staged, step_dt(s), force_u=fu, force_v=fv, force_w=fw)
      call fluid_project(staged)
      call fluid_finish_step(staged)
    end do
    velocity = max(full_difference(staged%u, fused%u), full_difference(staged%v, fused%v), &
                   full_difference(staged%w, fused%w))
    pressure = full_difference(staged%pressure, fused%pressure)
    history = max(field_difference(staged%explicit_old_u, fused%explicit_old_u, fused%grid), &
                  field_difference(staged%explicit_old_w, fused%explicit_old_w, fused%grid))
    call check_below(velocity, 1.0e-13_wp, 'staged_step_velocity_matches_fused_'//viscous_scheme//'_'// &
                     pressure_scheme//suffix)
    call check_below(pressure, 1.0e-13_wp, 'staged_step_pressure_matches_fused_'//viscous_scheme//'_'// &
                     pressure_scheme//suffix)
    call check_below(history, 1.0e-13_wp, 'staged_step_history_matches_fused_'//viscous_scheme//'_'// &
                     pressure_scheme//suffix)
    call check_below(abs(staged%time - fused%time) / fused%time, 1.0e-15_wp, 'staged_step_time_matches_fused_'// &
                     viscous_scheme//'_'//pressure_scheme//suffix)
    ! Every halo of the pressure is current after a step (copies of stored values: exact).
    halo_check = staged%pressure
    call exchange_halos(staged%grid, halo_check)
    call check_below(full_difference(halo_check, staged%pressure), 0.0_wp, 'staged_step_pressure_halos_current_'// &
                     viscous_scheme//'_'//pressure_scheme//suffix)
  end subroutine check_staged_matches_fused

  !> The incremental scheme in the periodic box: the same u and p as the pressure-free one after
  !> 6 steps (a sign or factor error in the old gradient or in the pressure update shows in p).
  subroutine check_incremental_matches_non_incremental(viscous_scheme, suffix)
    character(len=*), intent(in) :: viscous_scheme, suffix
    type(fluid_solver_t) :: plain, incremental
    real(wp), allocatable :: fu(:, :, :), fv(:, :, :), fw(:, :, :)
    integer :: s
    call make_case(plain, viscous_scheme, 'non_incremental', fu, fv, fw)
    call make_case(incremental, viscous_scheme, 'incremental', fu, fv, fw)
    do s = 1, 6
      call fluid_advance(plain, step_dt(s), fu, fv, fw)
      call fluid_advance(incremental, step_dt(s), fu, fv, fw)
    end do
    ! 1e-12: the incremental pressure is a running sum whose increments cancel the old value.
    call check_below(max(field_difference(incremental%u, plain%u, plain%grid), &
                         field_difference(incremental%v, plain%v, plain%grid), &
                         field_difference(incremental%w, plain%w, plain%grid)), 1.0e-12_wp, &
                     'incremental_pressure_same_velocity_in_periodic_box_'//viscous_scheme//suffix)
    call check_below(field_difference(incremental%pressure, plain%pressure, plain%grid), 1.0e-12_wp, &
                     'incremental_pressure_same_pressure_in_periodic_box_'//viscous_scheme//suffix)
  end subroutine check_incremental_matches_non_incremental

  !> Crank-Nicolson steps whose predictor is solved by the Jacobi solver above (through the
  !> fluid_predict hook) against the FFT solve: the same field to the iteration tolerance.
  subroutine check_own_predictor_solver(suffix)
    character(len=*), intent(in) :: suffix
    type(fluid_solver_t) :: reference, own
    type(jacobi_predictor_solver_t) :: jacobi
    real(wp), allocatable :: fu(:, :, :), fv(:, :, :), fw(:, :, :)
    integer :: s
    call make_case(reference, 'crank_nicolson', 'incremental', fu, fv, fw)
    call make_case(own, 'crank_nicolson', 'incremental', fu, fv, fw)
    do s = 1, 4
      call fluid_predict(reference, step_dt(s), force_u=fu, force_v=fv, force_w=fw)
      call fluid_project(reference)
      call fluid_finish_step(reference)
      call fluid_predict(own, step_dt(s), jacobi, fu, fv, fw)
      call fluid_project(own)
      call fluid_finish_step(own)
    end do
    call check_equal(jacobi%calls, 4, 'own_predictor_solver_called_once_per_step'//suffix)
    call check_below(max(field_difference(own%u, reference%u, reference%grid), &
                         field_difference(own%v, reference%v, reference%grid), &
                         field_difference(own%w, reference%w, reference%grid), &
                         field_difference(own%pressure, reference%pressure, reference%grid)), 1.0e-12_wp, &
                     'own_predictor_solver_matches_fft_solve'//suffix)
  end subroutine check_own_predictor_solver

  subroutine jacobi_solve(self, grid, poisson, alpha, u, v, w)
    class(jacobi_predictor_solver_t), intent(inout) :: self
    type(fluid_grid_t), intent(inout) :: grid
    type(poisson_fft_t), intent(inout) :: poisson
    real(wp), intent(in) :: alpha
    real(wp), intent(inout) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    self%calls = self%calls + 1
    if (.not. allocated(self%rhs)) then
      call allocate_field(grid, self%rhs); call allocate_field(grid, self%residual)
    end if
    call iterate(u); call iterate(v); call iterate(w)

  contains

    subroutine iterate(x)
      real(wp), intent(inout) :: x(0:, 0:, 0:)
      real(wp) :: diagonal, scale, update
      integer :: nx, ny, nz, sweep
      nx = grid%nx; ny = grid%ny; nz = grid%nz_local
      diagonal = 1.0_wp + 2.0_wp * alpha * (1.0_wp / grid%dx**2 + 1.0_wp / grid%dy**2 + 1.0_wp / grid%dz**2)
      self%rhs(1:nx, 1:ny, 1:nz) = x(1:nx, 1:ny, 1:nz)
      scale = global_max(maxval(abs(self%rhs(1:nx, 1:ny, 1:nz))))
      do sweep = 1, 200
        call exchange_halos(grid, x)
        call apply_predictor_operator(grid, alpha, x, self%residual)
        self%residual(1:nx, 1:ny, 1:nz) = (self%rhs(1:nx, 1:ny, 1:nz) - self%residual(1:nx, 1:ny, 1:nz)) / diagonal
        x(1:nx, 1:ny, 1:nz) = x(1:nx, 1:ny, 1:nz) + self%residual(1:nx, 1:ny, 1:nz)
        self%iterations = self%iterations + 1
        update = global_max(maxval(abs(self%residual(1:nx, 1:ny, 1:nz))))
        if (update <= self%tolerance * scale) exit
      end do
    end subroutine iterate
  end subroutine jacobi_solve
end module fluid_stage_checks
