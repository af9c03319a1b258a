!> The squeeze-film case of the immersed boundary for needles and disks (docs/validation.md,
!> "Lubrication", spheroid subsection): two equal spheroids of the paper's aspect ratio 5 approach
!> each other along x, each at speed U, their placement held fixed at a surface gap h and the flow run
!> to steady state at Re << 1 (the fixed-placement run of module squeeze_case). Configurations (the
!> closest points are the bodies' extreme points along x by symmetry):
!>   needle 'tip'      both axes along x: tip to tip (umbilics, radius of curvature b^2/a);
!>   needle 'crossed'  axes along y and z: equator to equator, crossed at right angles;
!>   needle 'parallel' both axes along y: equator to equator, side by side;
!>   disk 'face'       both axes along x: face to face (umbilics, radius of curvature b^2/a, here
!>                     a the half thickness and b the radius);
!>   disk 'edge'       both axes along z: coplanar, rim to rim.
!>
!> Reference: the sub-grid model's near-contact resistance at the closest points (module lubrication),
!> R(h) = 6 pi mu [R_eff^2 / h + logarithmic terms], with the reduced radius from the curvature
!> tensors, R_eff^2 = 2 / (tr K sqrt(det K)), K = K_1 + K_2 on the common tangent plane. Its leading
!> term is the Reynolds squeeze film of the gap h + x.K.x/2: p = 6 mu v_n / (tr K h(x)^2) solves
!> div(h^3 grad p) = 12 mu v_n (Reynolds 1886) and integrates to F = 12 pi mu v_n / (h tr K sqrt(det K));
!> for K isotropic (2/a I, two spheres) it is Cox & Brenner's 6 pi mu (a/2)^2 v_n / h, for crossed
!> cylinders of radius R (K = I/R) the sphere-on-plane 6 pi mu R^2 v_n / h (Chan & Horn 1985,
!> J. Chem. Phys. 83, 5311). v_n = 2U. It is an asymptote (h small against every radius of
!> curvature of the film region), not an exact force at finite gaps, so the table compares the
!> rise of the force from the widest gap, F(h) - F(h_1), with R(h) - R(h_1), as for spheres.
module spheroid_squeeze_case
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use wall_clock, only: wall_time
  use error_handling, only: fatal
  use text_format, only: real_text
  use fluid_solver, only: fluid_solver_t
  use spheroid, only: make_spheroid
  use quaternion, only: quaternion_normalise
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid
  use closest_points, only: closest_points_t, find_closest_points
  use immersed_scene, only: prescribed_motion_t
  use lubrication, only: lubrication_model_t, lubrication_geometry_t, lubrication_geometry, lubrication_resistance
  use squeeze_case, only: squeeze_case_t, squeeze_result_t, squeeze_fluid, squeeze_hold_to_steady_state, &
                          squeeze_speed, squeeze_dynamic_viscosity
  implicit none
  private
  public :: spheroid_squeeze_case_t, spheroid_squeeze_result_t, run_spheroid_squeeze, spheroid_squeeze_configurations, &
            spheroid_squeeze_box

  !> The five configurations of the module header, in table order.
  character(len=8), parameter :: spheroid_squeeze_configurations(5) = &
      [character(len=8) :: 'tip', 'crossed', 'parallel', 'face', 'edge']

  type :: spheroid_squeeze_case_t
    character(len=8) :: configuration = 'crossed'   !< one of spheroid_squeeze_configurations
    real(wp) :: radius_cells = 6.0_wp               !< r / dx, volume-equivalent radius (a b^2 = r^3)
    real(wp) :: gap_cells = 2.0_wp                  !< h / dx, surface gap
    integer :: cells(3) = 0                         !< box in cells; 0: spheroid_squeeze_box
    type(squeeze_case_t) :: run                     !< coupling, nu dt/dx^2, steady tolerance, offset
  end type spheroid_squeeze_case_t

  type :: spheroid_squeeze_result_t
    type(squeeze_result_t) :: resolved            !< force (N, (F_2x - F_1x)/2), steps, steady, cell
    real(wp) :: model_force = 0                   !< N, R(h) 2U of module lubrication
    real(wp) :: leading_force = 0                 !< N, 6 pi mu R_eff^2 2U / h (the Reynolds film alone)
    type(lubrication_geometry_t) :: geometry      !< R_eff and the mean radii a_i at the closest points
    real(wp) :: gap = 0                           !< m, from the closest points of the placement
    real(wp) :: semi_axes(2) = 0                  !< m, a (symmetry axis) and b
    integer :: cells(3) = 0                       !< the box used
    real(wp) :: reynolds = 0                      !< 2 U max(a, b) / nu
  end type spheroid_squeeze_result_t

  real(wp), parameter :: kinematic_viscosity = 1.0e-6_wp   !< m^2/s, module squeeze_case's water

contains

  !> A box for the configuration (cells): about 20 cells of fluid beyond the bodies across the
  !> approach and 40 cells of fluid between the pair and its periodic image along x.
  pure function spheroid_squeeze_box(configuration, radius_cells) result(cells)
    character(len=*), intent(in) :: configuration
    real(wp), intent(in) :: radius_cells
    integer :: cells(3)
    real(wp) :: long, short
    ! The long and short semi-axes (aspect 5, a b^2 = r^3): needle a = 5^(2/3) r, b = 5^(-1/3) r;
    ! disk b = 5^(1/3) r, a = 5^(-2/3) r.
    long = radius_cells * 5.0_wp**(2.0_wp / 3.0_wp)
    short = radius_cells * 5.0_wp**(-1.0_wp / 3.0_wp)
    if (configuration == 'face' .or. configuration == 'edge') then
      long = radius_cells * 5.0_wp**(1.0_wp / 3.0_wp)
      short = radius_cells * 5.0_wp**(-2.0_wp / 3.0_wp)
    end if
    select case (trim(configuration))
    case ('tip')
      cells = [even(4 * long + 40), even(2 * short + 20), even(2 * short + 20)]
    case ('crossed', 'face')
      cells = [even(4 * short + 40), even(2 * long + 20), even(2 * long + 20)]
    case ('parallel')
      cells = [even(4 * short + 40), even(2 * long + 20), even(2 * short + 20)]
    case default   ! 'edge'
      cells = [even(4 * long + 40), even(2 * long + 20), even(2 * short + 20)]
    end select
  contains
    pure integer function even(length)
      real(wp), intent(in) :: length
      even = 4 * ceiling(length / 4)
    end function even
  end function spheroid_squeeze_box

  !> Run one configuration at one gap to steady state (collective).
  subroutine run_spheroid_squeeze(case, result)
    type(spheroid_squeeze_case_t), intent(in) :: case
    type(spheroid_squeeze_result_t), intent(out) :: result
    type(fluid_solver_t) :: solver
    type(prescribed_motion_t) :: motion(2)
    type(rigid_body_t) :: bodies(2)
    type(closest_points_t) :: contact
    type(lubrication_model_t) :: model
    character(len=8) :: shape
    real(wp) :: h, radius, gap, t0, lengths(3), orientation(4, 2), extent
    integer :: n

    t0 = wall_time()
    if (.not. any(spheroid_squeeze_configurations == case%configuration)) &
      call fatal('spheroid squeeze: configuration = '''//trim(case%configuration)// &
                 '''; allowed: tip, crossed, parallel, face, edge')
    if (.not. (case%gap_cells > 0.0_wp)) &
      call fatal('spheroid squeeze: gap_cells = '//real_text(case%gap_cells)//'; allowed: > 0 (cells)')
    result%cells = case%cells
    if (any(case%cells <= 0)) result%cells = spheroid_squeeze_box(case%configuration, case%radius_cells)
    call squeeze_fluid(result%cells, solver, lengths, case%run%pressure_scheme)

    h = solver%grid%dx
    radius = case%radius_cells * h
    gap = case%gap_cells * h
    shape = shape_of(case%configuration)
    ! Body x (the symmetry axis) -> lab x, y or z.
    select case (trim(case%configuration))
    case ('tip', 'face')
      orientation(:, 1) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
      orientation(:, 2) = orientation(:, 1)
    case ('crossed')
      orientation(:, 1) = quaternion_normalise([1.0_wp, 0.0_wp, 0.0_wp, 1.0_wp])    ! x -> y
      orientation(:, 2) = quaternion_normalise([1.0_wp, 0.0_wp, -1.0_wp, 0.0_wp])   ! x -> z
    case ('parallel')
      orientation(:, 1) = quaternion_normalise([1.0_wp, 0.0_wp, 0.0_wp, 1.0_wp])
      orientation(:, 2) = orientation(:, 1)
    case default   ! 'edge'
      orientation(:, 1) = quaternion_normalise([1.0_wp, 0.0_wp, -1.0_wp, 0.0_wp])
      orientation(:, 2) = orientation(:, 1)
    end select
    do n = 1, 2
      motion(n)%shape = make_spheroid(trim(shape), radius, 1000.0_wp)   ! density unused: the motion is prescribed
      motion(n)%orientation = orientation(:, n)
      extent = motion(n)%shape%b
      if (case%configuration == 'tip' .or. case%configuration == 'face') extent = motion(n)%shape%a
      motion(n)%centre = 0.5_wp * lengths + case%run%offset_cells * h
      motion(n)%centre(1) = motion(n)%centre(1) + (2 * n - 3) * (extent + 0.5_wp * gap)
      motion(n)%velocity = [(3 - 2 * n) * squeeze_speed, 0.0_wp, 0.0_wp]   ! body 1 along +x, body 2 along -x
      call rigid_body_of_spheroid(bodies(n), motion(n)%shape, motion(n)%centre, motion(n)%orientation)
    end do
    result%semi_axes = [motion(1)%shape%a, motion(1)%shape%b]
    if (2.0_wp * minval(result%semi_axes) < 4.0_wp * h) &
      call fatal('spheroid squeeze: radius_cells = '//real_text(case%radius_cells)//' makes the '//trim(shape)// &
                 ' thinner than the 4 cells the immersed boundary needs; allowed: needle r/dx >= 3.42, disk r/dx >= 5.85')

    ! The model at the closest points of the placement.
    call find_closest_points(motion(1)%shape, motion(1)%centre, motion(1)%orientation, motion(2)%shape, &
                             motion(2)%centre, motion(2)%orientation, contact)
    if (.not. contact%converged) call fatal('spheroid squeeze: closest points: '//trim(contact%message))
    result%gap = contact%gap
    result%geometry = lubrication_geometry(motion(1)%shape, bodies(1), motion(2)%shape, bodies(2), contact)
    model%dynamic_viscosity = squeeze_dynamic_viscosity
    result%model_force = lubrication_resistance(model, result%geometry, contact%gap) * 2.0_wp * squeeze_speed
    result%leading_force = 6.0_wp * pi * squeeze_dynamic_viscosity * result%geometry%reduced_radius**2 &
                           * 2.0_wp * squeeze_speed / contact%gap

    call squeeze_hold_to_steady_state(case%run, solver, motion, result%resolved)
    result%resolved%radius = radius
    result%resolved%gap_over_radius = gap / radius
    result%resolved%reference = result%model_force
    result%resolved%error = result%resolved%force / result%model_force - 1.0_wp
    result%reynolds = 2.0_wp * squeeze_speed * maxval(result%semi_axes) / kinematic_viscosity
    result%resolved%reynolds = result%reynolds
    result%resolved%wall_seconds = wall_time() - t0
  end subroutine run_spheroid_squeeze

  !> The body of a configuration: 'disk' for face and edge, else 'needle'.
  pure function shape_of(configuration) result(shape)
    character(len=*), intent(in) :: configuration
    character(len=8) :: shape
    shape = 'needle'
    if (configuration == 'face' .or. configuration == 'edge') shape = 'disk'
  end function shape_of
end module spheroid_squeeze_case
