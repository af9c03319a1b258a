!> The squeeze-film validation case of the immersed boundary (docs/validation.md, "Lubrication"):
!> two equal spheres of radius a on a line along x approach each other, each at speed U, in fluid
!> initially at rest, in Stokes flow (Re = 2 U a / nu below 1e-4). The geometry is held fixed at a
!> given surface gap h (the rigid velocities +U and -U are imposed on a fixed placement) and the
!> flow is run to steady state: at Re << 1 the quasi-steady force of an approach at gap h.
!>
!> Reference: the exact force of two equal spheres approaching along their line of centres in
!> unbounded fluid, F = 6 pi mu a U beta, with Brenner's bispherical-coordinate series (Brenner
!> 1961, Chem. Eng. Sci. 16, 242, the sphere moving toward a free surface, which is the symmetry
!> plane of the pair):
!>   beta = (4/3) sinh(al) sum_{n>=1} n (n+1) / ((2n-1)(2n+3))
!>          [ (4 cosh^2((n+1/2) al) + (2n+1)^2 sinh^2(al)) / (2 sinh((2n+1) al) - (2n+1) sinh(2 al)) - 1 ],
!> cosh(al) = 1 + h / (2a). Near contact beta = 1/(2 eps) - (9/20) ln eps - (3/56) eps ln eps + 1.346
!> (eps = h/a; Cox & Brenner 1967; Jeffrey & Onishi 1984; Costa et al. 2015, who quote the constant 1.346), which
!> tests/unit/test_lubrication checks against the series.
!> The box is 2 n_y cells long along x and n_y = box_diameters D wide: the periodic images of the
!> pair (a force dipole) change the force by a few per cent at the widest gaps (the table says so).
module squeeze_case
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use wall_clock, only: wall_time
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use spheroid, only: make_spheroid
  use immersed_boundary, only: ibm_settings_t
  use immersed_scene, only: prescribed_motion_t, immersed_scene_t, immersed_scene_create, immersed_step
  implicit none
  private
  public :: squeeze_case_t, squeeze_result_t, run_squeeze, brenner_squeeze_coefficient, squeeze_speed, &
            squeeze_dynamic_viscosity

  type :: squeeze_case_t
    real(wp) :: diameter_cells = 8.0_wp          !< D / dx
    real(wp) :: gap_cells = 2.0_wp               !< h / dx, surface gap
    integer :: width_cells = 32                  !< n_y = n_z; n_x = 2 n_y
    character(len=16) :: coupling = 'implicit'   !< immersed_boundary coupling
    real(wp) :: viscous_number = 0.06_wp         !< nu dt / dx^2 (AB2 explicit diffusion: below 1/12)
    real(wp) :: steady_tolerance = 1.0e-7_wp     !< relative change of the force per step at steady state
    integer :: max_steps = 20000
    real(wp) :: offset_cells(3) = [0.31_wp, 0.13_wp, 0.27_wp]   !< gap centre - box centre, cells
  end type squeeze_case_t

  type :: squeeze_result_t
    real(wp) :: force = 0                  !< N, resolved (F2_x - F1_x) / 2, > 0 resisting the approach
    real(wp) :: reference = 0              !< N, 6 pi mu a U beta (Brenner)
    real(wp) :: error = 0                  !< force / reference - 1
    real(wp) :: gap_over_radius = 0        !< eps = h / a
    real(wp) :: radius = 0                 !< m, a
    real(wp) :: cell = 0                   !< m, dx
    real(wp) :: reynolds = 0               !< 2 U a / nu
    integer :: steps = 0
    logical :: steady = .false.
    real(wp) :: wall_seconds = 0
  end type squeeze_result_t

  ! Water-like units; U a / nu = 1e-5 at D/dx = 8 on a 1 mm box.
  real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp, speed = 1.0e-7_wp
  real(wp), parameter :: squeeze_speed = speed                            !< m/s, U of each sphere
  real(wp), parameter :: squeeze_dynamic_viscosity = density * viscosity  !< Pa s, mu

contains

  !> Brenner's beta (module header) for two equal spheres at gap h / a = gap_over_radius > 0, summed
  !> until a term is below 1e-15 of the sum.
  pure real(wp) function brenner_squeeze_coefficient(gap_over_radius) result(beta)
    real(wp), intent(in) :: gap_over_radius
    real(wp) :: alpha, k, term, total
    integer :: n
    alpha = acosh(1.0_wp + 0.5_wp * gap_over_radius)
    total = 0
    do n = 1, 1000000
      k = 2.0_wp * n + 1.0_wp
      term = real(n, wp) * (n + 1) / ((2.0_wp * n - 1.0_wp) * (2.0_wp * n + 3.0_wp)) &
             * ((4.0_wp * cosh(0.5_wp * k * alpha)**2 + (k * sinh(alpha))**2) &
                / (2.0_wp * sinh(k * alpha) - k * sinh(2.0_wp * alpha)) - 1.0_wp)
      total = total + term
      if (abs(term) < 1.0e-15_wp * abs(total) .or. k * alpha > 700.0_wp) exit
    end do
    beta = 4.0_wp / 3.0_wp * sinh(alpha) * total
  end function brenner_squeeze_coefficient

  !> Run the case at one gap to steady state (collective).
  subroutine run_squeeze(case, result)
    type(squeeze_case_t), intent(in) :: case
    type(squeeze_result_t), intent(out) :: result
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(immersed_scene_t) :: scene
    type(prescribed_motion_t) :: motion(2)
    type(ibm_settings_t) :: settings
    real(wp) :: h, radius, gap, dt, force_old, force_new, t0, centres(3, 2), width
    integer :: step, n

    t0 = wall_time()
    width = box * case%width_cells / (2 * case%width_cells)   ! n_y cells over half the x length
    grid_cfg = grid_config_t(nx=2 * case%width_cells, ny=case%width_cells, nz=case%width_cells, length_x=box, &
                             length_y=width, length_z=width)
    fluid_cfg%density = density
    fluid_cfg%viscosity = viscosity
    fluid_cfg%viscous_scheme = 'explicit'
    fluid_cfg%pressure_scheme = 'incremental'
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0

    h = solver%grid%dx
    radius = 0.5_wp * case%diameter_cells * h
    gap = case%gap_cells * h
    do n = 1, 2
      motion(n)%shape = make_spheroid('sphere', radius, density)
      centres(:, n) = [0.5_wp * box, 0.5_wp * width, 0.5_wp * width] + case%offset_cells * h
      centres(1, n) = centres(1, n) + (2 * n - 3) * (radius + 0.5_wp * gap)
      motion(n)%velocity = [(3 - 2 * n) * speed, 0.0_wp, 0.0_wp]   ! body 1 along +x, body 2 along -x
      motion(n)%centre = centres(:, n)
    end do
    settings%coupling = case%coupling
    settings%max_sweeps = 100
    settings%fluid_density = density
    dt = case%viscous_number * h**2 / viscosity
    call hold_in_place(solver%time + dt)
    call immersed_scene_create(scene, solver, motion, settings, [0.0_wp, 0.0_wp, 0.0_wp])

    force_old = 0
    do step = 1, case%max_steps
      ! The placement of the step is c0 + U t at its end time: hold it at the fixed centres.
      call hold_in_place(solver%time + dt)
      scene%motion = motion
      call immersed_step(scene, solver, dt)
      force_new = 0.5_wp * (scene%force(1, 2) - scene%force(1, 1))
      result%steps = step
      if (step > 10 .and. abs(force_new - force_old) <= case%steady_tolerance * abs(force_new)) then
        result%steady = .true.
        exit
      end if
      force_old = force_new
    end do
    result%force = force_new
    result%gap_over_radius = gap / radius
    result%radius = radius
    result%cell = h
    result%reference = 6.0_wp * pi * density * viscosity * radius * speed &
                       * brenner_squeeze_coefficient(result%gap_over_radius)
    result%error = result%force / result%reference - 1.0_wp
    result%reynolds = 2.0_wp * speed * radius / viscosity
    result%wall_seconds = wall_time() - t0

  contains

    !> Set each body's c0 so that c0 + U time is its fixed centre.
    subroutine hold_in_place(time)
      real(wp), intent(in) :: time
      integer :: m
      do m = 1, 2
        motion(m)%centre = centres(:, m) - motion(m)%velocity * time
      end do
    end subroutine hold_in_place
  end subroutine run_squeeze
end module squeeze_case
