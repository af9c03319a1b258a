!> The validation case of the free particles (docs/validation.md, "Free particles"): one sphere
!> settling under gravity in the periodic cube (module resolved_hydrodynamics: its net weight W on
!> the sphere, the opposite drive -W / L^3 over the box), i.e. a simple-cubic array seen from the
!> sphere. At steady state the array's Stokes drag balances the weight,
!>   W = 6 pi mu a K U_s,   U_s = U_p - U_face,
!> U_face the flux through the box's x-face over its area (a plane the sphere never cuts, as in
!> sphere_array_case), so K is the same drag coefficient as the fixed array's, against Zick & Homsy
!> (1982, J. Fluid Mech. 115, 13, Table 2). Gravity along x; the weight makes U_s about 1e-7 m/s
!> (Re below 1e-4). Steady: the relative change of U_s per step below steady_tolerance.
!> Also the box's momentum rho_f dV sum_{fluid u nodes} u + m U_p (zero: no net force on the box),
!> over rho_f L^3 U_s, and what the u nodes that changed status during the run carried across that
!> budget's boundary: rho_f dV (sum of u over the nodes that became fluid, at the step they did,
!> less the sum of u over the nodes that stopped being fluid, at their last fluid step), over the
!> same, with the number of such changes.
!>
!> shape = 'needle' or 'disk' (aspect 5; volume-equivalent radius r from thin_cells, the thinnest
!> dimension in cells) with its symmetry axis turned by tilt_degrees about z away from gravity:
!> the body is free to translate and rotate, and the slip is a vector, U_s,i = U_p,i - U_face,i,
!> U_face,i the flux through the box's i-face over its area (planes the body never cuts). In the
!> periodic array the slip is U_s = M W with the box mobility, per body axis (periodic_slip_reference)
!>   6 pi mu r M_i = 1/c_i - 2.837 r/L + C_i (r/L)^3
!> (Hasimoto 1959, J. Fluid Mech. 5, 317: the O(r/L) term is the point-force lattice's, the same
!> for every shape), c_i the Oberbeck/Perrin coefficients of module stokes_resistance. The
!> body-frame slip over the body-frame weight gives the measured 6 pi mu r M_i (mobility_body).
!> A fore-aft symmetric body in a centrosymmetric array feels no torque while it translates, so it
!> does not turn; the grid's sampling asymmetry makes it turn slowly (turn_degrees over the run,
!> spin: its last |Omega| times the long semi-axis over |U_s|).
module settling_sphere_case
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use physical_constants, only: pi
  use parallel_env, only: global_sum
  use wall_clock, only: wall_time
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use forcing_driver, only: forcing_driver_t
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler, angular_velocity_lab
  use quaternion, only: quaternion_from_axis_angle, rotation_matrix
  use stokes_resistance, only: spheroid_resistance_coefficients
  use particle_system, only: particle_system_t, particle_models_t, particle_loads_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero
  use immersed_boundary, only: ibm_settings_t
  use immersed_geometry, only: node_fluid
  use resolved_hydrodynamics, only: resolved_hydrodynamics_t, resolved_hydrodynamics_create, &
                                    resolved_hydrodynamics_options_t
  implicit none
  private
  public :: settling_case_t, settling_result_t, run_settling_sphere, periodic_slip_reference, drift_angle_degrees

  type :: settling_case_t
    integer :: cells = 13                        !< cells per box edge
    real(wp) :: volume_fraction = 0.125_wp       !< phi = V_sphere / L^3
    real(wp) :: density_ratio = 2.72_wp          !< rho_p / rho_f
    logical :: stabilise = .true.                !< the added-mass stabilisation
    integer :: substeps = 4                      !< particle sub-steps per fluid step
    real(wp) :: viscous_number = 0.06_wp         !< nu dt / dx^2
    character(len=16) :: viscous_scheme = 'explicit'   !< &fluid viscous_scheme: 'explicit' | 'crank_nicolson'
    !> &fluid pressure_scheme: 'incremental' (the ladder's) or 'non_incremental' (the decks' default)
    character(len=16) :: pressure_scheme = 'incremental'
    real(wp) :: steady_tolerance = 1.0e-8_wp
    integer :: max_steps = 20000
    real(wp) :: offset_cells(3) = [0.13_wp, 0.27_wp, 0.41_wp]   !< sphere centre - box centre, cells
    character(len=8) :: shape = 'sphere'         !< 'sphere', or 'needle' / 'disk' of aspect 5
    real(wp) :: thin_cells = 0                   !< spheroids: thinnest dimension in cells (sets r)
    real(wp) :: tilt_degrees = 0                 !< spheroids: symmetry axis from gravity (x), turned about z
    real(wp) :: weight = 2.5e-12_wp              !< N, the net weight W (U_s about 1e-7 m/s, Re below 1e-4)
  end type settling_case_t

  type :: settling_result_t
    real(wp) :: drag_coefficient = 0       !< K = W / (6 pi mu a U_s)
    real(wp) :: diameter_cells = 0         !< D / dx
    real(wp) :: slip = 0                   !< m/s, U_s
    real(wp) :: momentum = 0               !< the box's momentum / (rho_f L^3 U_s)
    real(wp) :: status_momentum = 0        !< momentum the u nodes' status changes carried / (rho_f L^3 U_s)
    integer :: status_changes = 0          !< u nodes that became fluid or stopped being fluid, over the run
    real(wp) :: slip_vector(3) = 0         !< m/s, U_s per lab direction
    real(wp) :: weight(3) = 0              !< N, the net weight W (lab)
    real(wp) :: radius = 0                 !< m, volume-equivalent
    type(spheroid_t) :: body_shape         !< the body settled
    real(wp) :: box = 0                    !< m, L
    real(wp) :: viscosity = 0              !< Pa s, mu
    real(wp) :: rotation(3, 3) = 0         !< body to lab at the start
    real(wp) :: mobility_body(3) = 0       !< 6 pi mu r U_s,i / W_i along the body axes (start orientation)
    real(wp) :: turn_degrees = 0           !< angle the body turned over the run
    real(wp) :: spin = 0                   !< last |Omega| times the long semi-axis over |U_s|
    integer :: steps = 0
    logical :: steady = .false.
    real(wp) :: wall_seconds = 0
  end type settling_result_t

  ! Water-like units in a 1 mm cell, as sphere_array_case.
  real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp

contains

  !> Run the case to steady state (collective).
  subroutine run_settling_sphere(case, result)
    type(settling_case_t), intent(in) :: case
    type(settling_result_t), intent(out) :: result
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(forcing_driver_t) :: forcing                  ! inactive
    type(spheroid_t) :: shape(1)
    type(rigid_body_t) :: body(1)
    type(particle_models_t) :: models
    type(particle_system_t) :: system
    type(particle_loads_t) :: loads
    type(ibm_settings_t) :: settings
    type(resolved_hydrodynamics_t) :: provider
    real(wp) :: radius, gravity(3), dt, slip(3), slip_old(3), u_face(3), fluid_flux, t0, start(4), overlap
    real(wp) :: weight_body(3), slip_body(3), status_flux
    real(wp), allocatable :: u_before(:, :, :)
    logical, allocatable :: fluid_before(:, :, :), fluid_after(:, :, :)
    integer :: step, substep, n, nz

    t0 = wall_time()
    if (.not. abs(case%density_ratio - 1.0_wp) > 1.0e-3_wp) &
      call fatal('settling_sphere_case: density_ratio 1 has no net weight to settle under')
    n = case%cells
    grid_cfg = grid_config_t(nx=n, ny=n, nz=n, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = density
    fluid_cfg%viscosity = viscosity
    fluid_cfg%viscous_scheme = case%viscous_scheme
    fluid_cfg%pressure_scheme = case%pressure_scheme
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
    nz = solver%grid%nz_local
    start = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
    select case (trim(case%shape))
    case ('sphere')
      radius = (3.0_wp * case%volume_fraction / (4.0_wp * pi))**(1.0_wp / 3.0_wp) * box
    case ('needle', 'disk')
      if (.not. case%thin_cells > 0.0_wp) call fatal('settling_sphere_case: thin_cells must be > 0 for a spheroid')
      ! Aspect 5, r^3 = a b^2: the needle's thin dimension 2b = 2 r / 5^(1/3), the disk's 2a = 2 r / 25^(1/3).
      radius = 0.5_wp * case%thin_cells * solver%grid%dx * merge(5.0_wp**(1.0_wp / 3.0_wp), 25.0_wp**(1.0_wp / 3.0_wp), &
                                                                 trim(case%shape) == 'needle')
      start = quaternion_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], case%tilt_degrees * pi / 180.0_wp)
    case default
      call fatal('settling_sphere_case: shape '''//trim(case%shape)//''' is not sphere, needle or disk')
    end select
    shape(1) = make_spheroid(trim(case%shape), radius, case%density_ratio * density)
    call require_inside_faces(shape(1), start, 0.5_wp * box + case%offset_cells * solver%grid%dx, solver%grid%dx)
    call rigid_body_of_spheroid(body(1), shape(1), 0.5_wp * box + case%offset_cells * solver%grid%dx, &
                                start, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
    models%integrator = integrator_euler
    call particle_system_create(system, shape, body, models, [box, box, box])
    call particle_system_interact(system, 1.0_wp)
    gravity = [case%weight / ((case%density_ratio - 1.0_wp) * density * shape(1)%volume), 0.0_wp, 0.0_wp]
    settings%coupling = 'implicit'
    settings%tolerance = 1.0e-12_wp
    settings%max_sweeps = 100
    settings%fluid_density = density
    call resolved_hydrodynamics_create(provider, solver, system, resolved_hydrodynamics_options_t(settings=settings, &
                                       stabilise=case%stabilise, gravity=gravity))
    call provider%prepare(solver, system)
    loads = particle_loads_zero(1)
    dt = case%viscous_number * solver%grid%dx**2 / viscosity
    slip_old = 0
    slip = 0
    status_flux = 0
    do step = 1, case%max_steps
      associate (status => provider%scene%ibm%geometry%component(1)%status)
        fluid_before = status(1:n, 1:n, 1:nz) == node_fluid
      end associate
      u_before = solver%u(1:n, 1:n, 1:nz)
      call provider%fluid_step(solver, forcing, system, dt)
      associate (status => provider%scene%ibm%geometry%component(1)%status)
        fluid_after = status(1:n, 1:n, 1:nz) == node_fluid
      end associate
      result%status_changes = result%status_changes + count(fluid_before .neqv. fluid_after)
      status_flux = status_flux + sum(solver%u(1:n, 1:n, 1:nz), mask=fluid_after .and. .not. fluid_before) &
                    - sum(u_before, mask=fluid_before .and. .not. fluid_after)
      do substep = 1, case%substeps
        call provider%loads(system, real(substep - 1, wp) / case%substeps, loads)
        call particle_system_step(system, dt / case%substeps, loads)
      end do
      u_face = face_velocity(solver)
      slip = system%bodies(1)%velocity - u_face
      result%steps = step
      if (step > 50 .and. norm2(slip - slip_old) <= case%steady_tolerance * norm2(slip)) then
        result%steady = .true.
        exit
      end if
      slip_old = slip
    end do
    result%slip = slip(1)
    result%slip_vector = slip
    result%drag_coefficient = case%weight / (6.0_wp * pi * density * viscosity * radius * slip(1))
    result%diameter_cells = 2.0_wp * radius / solver%grid%dx
    result%weight = provider%weight(:, 1)
    result%radius = radius
    result%body_shape = shape(1)
    result%box = box
    result%viscosity = density * viscosity
    result%rotation = rotation_matrix(start)
    weight_body = matmul(result%weight, result%rotation)
    slip_body = matmul(slip, result%rotation)
    where (abs(weight_body) > 1.0e-6_wp * norm2(weight_body))
      result%mobility_body = 6.0_wp * pi * result%viscosity * radius * slip_body / weight_body
    end where
    overlap = min(1.0_wp, abs(dot_product(start, system%bodies(1)%quaternion)))
    result%turn_degrees = 2.0_wp * acos(overlap) * 180.0_wp / pi
    result%spin = norm2(angular_velocity_lab(system%bodies(1))) * max(shape(1)%a, shape(1)%b) / norm2(slip)
    associate (status => provider%scene%ibm%geometry%component(1)%status)
      fluid_flux = global_sum(sum(solver%u(1:n, 1:n, 1:nz), mask=status(1:n, 1:n, 1:nz) == node_fluid))
    end associate
    result%momentum = (density * solver%grid%dx * solver%grid%dy * solver%grid%dz * fluid_flux &
                       + system%bodies(1)%mass * system%bodies(1)%velocity(1)) / (density * box**3 * slip(1))
    result%status_changes = nint(global_sum(real(result%status_changes, wp)))
    result%status_momentum = density * solver%grid%dx * solver%grid%dy * solver%grid%dz * global_sum(status_flux) &
                             / (density * box**3 * slip(1))
    result%wall_seconds = wall_time() - t0
  end subroutine run_settling_sphere

  !> The slip is measured on the box's faces: the body (with a ghost layer of 2 cells) must not reach them.
  subroutine require_inside_faces(shape, orientation, centre, dx)
    type(spheroid_t), intent(in) :: shape
    real(wp), intent(in) :: orientation(4), centre(3), dx
    real(wp) :: axis(3), reach(3)
    character(len=200) :: text
    axis = matmul(rotation_matrix(orientation), [1.0_wp, 0.0_wp, 0.0_wp])
    ! Half extent of the spheroid along lab direction i: sqrt(a^2 e_i^2 + b^2 (1 - e_i^2)), e its axis.
    reach = sqrt(shape%a**2 * axis**2 + shape%b**2 * (1.0_wp - axis**2)) + 2.0_wp * dx
    if (all(centre - reach > 0.0_wp .and. centre + reach < box)) return
    write(text, '(a,3f7.2,a)') 'settling_sphere_case: the body reaches a box face (half extents in cells', reach / dx, &
        '): a larger box (cells) or a smaller body'
    call fatal(trim(text))
  end subroutine require_inside_faces

  !> The fluid's flux through the box's x-, y- and z-faces (the planes i, j, k = n at the box edge)
  !> over their area (collective: the z-face lies on the rank holding global k = n).
  function face_velocity(solver) result(u_face)
    type(fluid_solver_t), intent(in) :: solver
    real(wp) :: u_face(3), local(3)
    integer :: n, nz
    n = solver%grid%nx
    nz = solver%grid%nz_local
    local(1) = sum(solver%u(n, 1:n, 1:nz))
    local(2) = sum(solver%v(1:n, n, 1:nz))
    local(3) = 0
    if (solver%grid%z_offset + nz == solver%grid%nz) local(3) = sum(solver%w(1:n, 1:n, nz))
    u_face = [global_sum(local(1)), global_sum(local(2)), global_sum(local(3))] / real(n * n, wp)
  end function face_velocity

  !> The slip velocity (lab, m/s) of a spheroid settling under the net weight (lab, N) in the
  !> periodic cube of edge box (module header): U_s = R diag(M_i) R^T W, R = rotation (body to lab),
  !> 6 pi mu r M_i = 1/c_i - 2.837 r/L + cubic_i (r/L)^3 with c_i the Oberbeck/Perrin coefficients
  !> [axial, transverse]; cubic = 0 keeps Hasimoto's leading term only.
  pure function periodic_slip_reference(shape, rotation, weight, viscosity, box, cubic) result(slip)
    type(spheroid_t), intent(in) :: shape
    real(wp), intent(in) :: rotation(3, 3), weight(3), viscosity, box, cubic(2)
    real(wp) :: slip(3)
    real(wp), parameter :: hasimoto = 2.837_wp   ! 1.7601 (4 pi / 3)^(1/3), Hasimoto 1959
    real(wp) :: c(4), r, mobility(3)
    c = spheroid_resistance_coefficients(shape%a, shape%b)
    r = (shape%a * shape%b**2)**(1.0_wp / 3.0_wp)
    mobility = (1.0_wp / c([1, 2, 2]) - hasimoto * r / box + cubic([1, 2, 2]) * (r / box)**3) &
               / (6.0_wp * pi * viscosity * r)
    slip = matmul(rotation, mobility * matmul(weight, rotation))
  end function periodic_slip_reference

  !> The angle (degrees) between a velocity and the direction of the weight.
  pure real(wp) function drift_angle_degrees(velocity, weight) result(angle)
    real(wp), intent(in) :: velocity(3), weight(3)
    angle = acos(max(-1.0_wp, min(1.0_wp, dot_product(velocity, weight) / (norm2(velocity) * norm2(weight))))) &
            * 180.0_wp / pi
  end function drift_angle_degrees
end module settling_sphere_case
