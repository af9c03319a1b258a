! checks: 32
!> The image-point fallback of immersed_geometry (docs/theory.md, "Immersed boundary geometry"): when the segment from the
!> surface point B to the image point M enters another body, M is moved back along n to the middle
!> of the gap and the ghost row extrapolates linearly with kappa = d_G/d_M. A needle and a disk one
!> cell apart (surface gap 1.0 h along the line of centres), at a random sub-cell position and
!> orientation, away from the periodic wrap:
!>  - explicit coupling (image point 1.5 h out, which reaches across a 1-cell gap): the fallback is
!>    taken, and n_fallback counts exactly the flagged records; with pure mirrors (implicit
!>    coupling, d_M = d_G < h) it is not, as the ghost layer is less than a cell deep;
!>  - every flagged record: d_M below the unmoved image distance, B + 2 d_M n on the other body's
!>    surface (implicit function 0 to 1e-9: the mid-gap), M outside both bodies, kappa = d_G/d_M;
!>  - a linear field (the rigid motion U0 + Omega x (x - X0) shared by both bodies, each body moving
!>    with it): the explicit imposition leaves it unchanged (every ghost row, fallback rows included,
!>    already holds, to 1e-12 of the velocity scale), and at a gap of 0.5 h the implicit coupling,
!>    whose pure mirrors now fall back, recovers it from zeroed ghost values;
!>  - below the saturation gap s_min = 0.5 h (a gap of 0.2 h, implicit coupling): the rows whose
!>    image segment enters the sphere within s_min are flagged saturated and counted, leave the
!>    fluid out (kappa = 0) and take the Couette value u_G = u_B - (d_G/s_min)(u_B' - u_B), u_B' the
!>    sphere's rigid velocity where the ray B + s n enters it (found here by bisection of its implicit
!>    function, independently of the geometry module); with the two bodies in different rigid motions
!>    and random fluid values the imposed ghost values equal that hand-computed value to 1e-12 of the
!>    velocity scale (the linear field is not recovered there: a saturated row's gain is d_G/s_min
!>    where the linear field needs d_G/s; the rows are exact for it only at s = s_min).
program test_immersed_fallback
  use agglo_kinds, only: wp, i8
  use vector_algebra, only: cross
  use parallel_env, only: parallel_start
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: random_orientation, rotate_to_body, rotate_to_lab
  use spheroid, only: make_spheroid, implicit_function
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use immersed_geometry, only: immersed_body_t, immersed_geometry_t, node_position, fallback_count, saturated_count
  use immersed_boundary, only: immersed_boundary_t, imposition_report_t
  use immersed_placement, only: ibm_set_bodies
  use immersed_imposition, only: ibm_impose
  use immersed_loads, only: ibm_begin_step
  use test_framework, only: test_start, test_finish, check_below, check_above, check_equal
  implicit none
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  type(immersed_boundary_t) :: ibm
  type(immersed_body_t) :: bodies(2)
  type(imposition_report_t) :: report
  real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :), u0(:, :, :), v0(:, :, :), w0(:, :, :)
  real(wp) :: velocity(3, 2), angular_velocity(3, 2), dx, direction(3), reference_point(3), omega(3), base(3)
  real(wp) :: change, worst_surface, worst_kappa, worst_outside, largest_fraction
  real(wp) :: worst_opposite, worst_gain, worst_couette, saturation_gap
  integer :: case_index, c, g, flagged, n, saturated
  character(len=8), parameter :: couplings(4) = [character(len=8) :: 'explicit', 'implicit', 'implicit', 'implicit']
  real(wp), parameter :: gaps(4) = [1.0_wp, 1.0_wp, 0.5_wp, 0.2_wp]   ! surface gap in cells
  character(len=40) :: label

  call parallel_start()
  call test_start('immersed_fallback')
  call stream_seed(stream, 41_i8, stream_id=2)
  call grid_create(grid, 32, 32, 32, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  dx = grid%dx
  call allocate_field(grid, u); call allocate_field(grid, v); call allocate_field(grid, w)
  bodies(1)%shape = make_spheroid('needle', 3.0_wp * dx, 1000.0_wp, 3.0_wp)
  bodies(2)%shape = make_spheroid('sphere', 3.0_wp * dx, 1000.0_wp)
  reference_point = 16.0_wp * dx
  omega = [3.0_wp, -1.0_wp, 2.0_wp]
  base = [1.0e-3_wp, -2.0e-3_wp, 0.5e-3_wp]
  saturation_gap = 0.5_wp * dx
  do case_index = 1, 4
    write(label, '(a,a,f3.1,a)') trim(couplings(case_index)), '_gap_', gaps(case_index), 'h'
    ! The needle near the box centre; the sphere on a random direction at the given surface gap
    ! from it (its centre on the needle's outward normal at the point of the needle hit by that
    ! direction, so the gap is the surface distance).
    bodies(1)%centre = reference_point + [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)] * dx
    bodies(1)%orientation = random_orientation(stream)
    direction = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    direction = direction / norm2(direction)
    bodies(2)%centre = sphere_at_gap(bodies(1), direction, bodies(2)%shape%a + gaps(case_index) * dx)
    do n = 1, 2
      velocity(:, n) = base + cross(omega, bodies(n)%centre - reference_point)
      angular_velocity(:, n) = omega
    end do
    ibm = immersed_boundary_t()
    ibm%settings%coupling = couplings(case_index)
    call ibm_set_bodies(ibm, grid, bodies, velocity, angular_velocity, classify=.true.)

    ! Counts: the flagged records are the counted ones.
    flagged = 0
    do c = 1, 3
      flagged = flagged + count(ibm%geometry%component(c)%ghost(1:ibm%geometry%component(c)%n_ghost)%fallback)
    end do
    call check_equal(fallback_count(ibm%geometry), flagged, trim(label)//'_fallbacks_counted')
    saturated = 0
    do c = 1, 3
      saturated = saturated + count(ibm%geometry%component(c)%ghost(1:ibm%geometry%component(c)%n_ghost)%saturated)
    end do
    call check_equal(saturated_count(ibm%geometry), saturated, trim(label)//'_saturated_counted')
    write(*, '(a,a,i0,a,i0)') trim(label), ': fallback rows ', flagged, ' of ghost rows ', &
        sum(ibm%geometry%component(:)%n_ghost)
    if (case_index == 2) then
      call check_equal(flagged, 0, trim(label)//'_pure_mirror_needs_no_fallback')
      cycle
    end if
    call check_above(real(flagged, wp), 1.0_wp, trim(label)//'_fallback_taken')

    ! Geometry of every flagged record.
    worst_surface = 0; worst_kappa = 0; worst_outside = huge(1.0_wp); largest_fraction = 0
    do c = 1, 3
      do g = 1, ibm%geometry%component(c)%n_ghost
        associate (r => ibm%geometry%component(c)%ghost(g))
          if (.not. r%fallback) cycle
          n = 3 - r%body
          worst_surface = max(worst_surface, abs(implicit_function(bodies(n)%shape, &
              rotate_to_body(bodies(n)%orientation, r%surface_point + 2.0_wp * r%image_distance * r%normal &
                                                    - bodies(n)%centre))))
          if (r%saturated) then
            worst_kappa = max(worst_kappa, abs(r%extrapolation))
          else
            worst_kappa = max(worst_kappa, abs(r%extrapolation - r%distance / r%image_distance))
          end if
          worst_outside = min(worst_outside, implicit_function(bodies(1)%shape, rotate_to_body(bodies(1)%orientation, &
              r%image_point - bodies(1)%centre)), implicit_function(bodies(2)%shape, &
              rotate_to_body(bodies(2)%orientation, r%image_point - bodies(2)%centre)))
          largest_fraction = max(largest_fraction, r%image_distance / unmoved_image_distance(r%distance))
        end associate
      end do
    end do
    call check_below(worst_surface, 1.0e-9_wp, trim(label)//'_image_point_at_mid_gap')
    call check_below(worst_kappa, 1.0e-14_wp, trim(label)//'_kappa_is_dG_over_dM')
    call check_above(worst_outside, 0.0_wp, trim(label)//'_image_point_outside_both_bodies')
    call check_below(largest_fraction, 1.0_wp, trim(label)//'_image_point_moved_back')

    ! The linear field: unchanged by the explicit imposition; recovered by the implicit one. Not
    ! below s_min: a saturated row takes the gain d_G/s_min where the linear field needs d_G/s, and
    ! the implicit rows whose stencils hold it inherit the difference.
    if (case_index == 4) call check_couette_rows()
    if (case_index == 4) cycle
    call fill_linear(1, u); call fill_linear(2, v); call fill_linear(3, w)
    u0 = u; v0 = v; w0 = w
    if (couplings(case_index) == 'implicit') then
      call zero_ghosts(1, u); call zero_ghosts(2, v); call zero_ghosts(3, w)
    end if
    call ibm_begin_step(ibm, grid, u, v, w)
    call ibm_impose(ibm, grid, u, v, w, report)
    ! Inner nodes only: the imposition ends with the periodic halo exchange, and the linear field
    ! is not periodic.
    change = max(maxval(abs(u(1:32, 1:32, 1:32) - u0(1:32, 1:32, 1:32))), &
                 maxval(abs(v(1:32, 1:32, 1:32) - v0(1:32, 1:32, 1:32))), &
                 maxval(abs(w(1:32, 1:32, 1:32) - w0(1:32, 1:32, 1:32)))) / report%velocity_scale
    call check_below(change, 1.0e-12_wp, trim(label)//'_ghost_values_exact_for_linear_field')
    call check_equal(saturated, 0, trim(label)//'_no_saturated_row_above_half_a_cell')
  end do
  call test_finish()

contains

  !> Below the saturation gap: the Couette rows, with the bodies in different rigid motions.
  subroutine check_couette_rows()
    write(*, '(a,a,i0)') trim(label), ': saturated rows ', saturated
    call check_above(real(saturated, wp), 1.0_wp, trim(label)//'_saturated_rows_taken')
    worst_opposite = 0; worst_gain = 0
    do c = 1, 3
      do g = 1, ibm%geometry%component(c)%n_ghost
        associate (r => ibm%geometry%component(c)%ghost(g))
          if (.not. r%saturated) cycle
          n = 3 - r%body
          worst_opposite = max(worst_opposite, abs(norm2(r%opposite_point - r%surface_point) &
                                                   - entry_distance(n, r%surface_point, r%normal)) / dx)
          worst_gain = max(worst_gain, abs(r%couette_gain - r%distance / saturation_gap))
          if (.not. r%fallback .or. r%opposite_body /= n) worst_gain = huge(1.0_wp)
        end associate
      end do
    end do
    call check_below(worst_opposite, 1.0e-9_wp, trim(label)//'_opposite_point_where_the_ray_enters')
    call check_below(worst_gain, 1.0e-14_wp, trim(label)//'_couette_gain_is_dG_over_smin')
    velocity(:, 1) = [2.0e-3_wp, -1.0e-3_wp, 0.5e-3_wp]
    velocity(:, 2) = [-1.5e-3_wp, 0.5e-3_wp, 1.0e-3_wp]
    angular_velocity(:, 1) = [1.0_wp, 4.0_wp, -2.0_wp]
    angular_velocity(:, 2) = [-3.0_wp, 0.5_wp, 2.5_wp]
    call ibm_set_bodies(ibm, grid, bodies, velocity, angular_velocity, classify=.false.)
    call fill_random(u); call fill_random(v); call fill_random(w)
    call ibm_begin_step(ibm, grid, u, v, w)
    call ibm_impose(ibm, grid, u, v, w, report)
    worst_couette = 0
    call compare_couette(1, u); call compare_couette(2, v); call compare_couette(3, w)
    call check_below(worst_couette / report%velocity_scale, 1.0e-12_wp, trim(label)//'_saturated_rows_take_couette_value')
  end subroutine check_couette_rows

  !> The image distance the fallback shortened: d_G (pure mirror) or max(d_G, 1.5 h) (image point).
  real(wp) function unmoved_image_distance(distance)
    real(wp), intent(in) :: distance
    unmoved_image_distance = distance
    if (ibm%settings%coupling == 'explicit') unmoved_image_distance = max(distance, 1.5_wp * dx)
  end function unmoved_image_distance

  !> Centre of a sphere of radius `reach` - gap beyond the needle's surface point hit by the ray
  !> from the needle's centre along `direction`, on the needle's normal there: at surface gap `gap`.
  function sphere_at_gap(needle, direction, reach) result(centre)
    type(immersed_body_t), intent(in) :: needle
    real(wp), intent(in) :: direction(3), reach
    real(wp) :: centre(3), body_direction(3), t, point(3), normal(3)
    body_direction = rotate_to_body(needle%orientation, direction)
    ! F(t d) = 0: t = 1 / sqrt(d1^2/a^2 + (d2^2 + d3^2)/b^2).
    t = 1.0_wp / sqrt(body_direction(1)**2 / needle%shape%a**2 + &
                      (body_direction(2)**2 + body_direction(3)**2) / needle%shape%b**2)
    point = t * body_direction
    normal = [point(1) / needle%shape%a**2, point(2:3) / needle%shape%b**2]
    normal = normal / norm2(normal)
    centre = needle%centre + rotate_to_lab(needle%orientation, point + reach * normal)
  end function sphere_at_gap

  !> Component c of U0 + Omega x (x - X0) at every node of the field, halos included.
  subroutine fill_linear(c, field)
    integer, intent(in) :: c
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: i, j, k
    real(wp) :: full(3)
    do k = 0, grid%nz_local + 1
      do j = 0, grid%ny + 1
        do i = 0, grid%nx + 1
          full = base + cross(omega, node_position(grid, c, i, j, k) - reference_point)
          field(i, j, k) = full(c)
        end do
      end do
    end do
  end subroutine fill_linear

  !> Distance along the ray b + s n (s in [0, 0.5 h]) at which it enters body n: bisection of the
  !> body's implicit function (positive outside), 200 halvings.
  real(wp) function entry_distance(n, b, normal) result(s)
    integer, intent(in) :: n
    real(wp), intent(in) :: b(3), normal(3)
    real(wp) :: low, high
    integer :: iteration
    low = 0
    high = saturation_gap
    do iteration = 1, 200
      s = 0.5_wp * (low + high)
      if (implicit_function(bodies(n)%shape, rotate_to_body(bodies(n)%orientation, b + s * normal - bodies(n)%centre)) &
          > 0.0_wp) then
        low = s
      else
        high = s
      end if
    end do
  end function entry_distance

  !> Largest |u_G - (u_B - (d_G/s_min)(u_B' - u_B))| over the saturated rows of component c (into
  !> worst_couette), the body velocities and B' computed here.
  subroutine compare_couette(c, field)
    integer, intent(in) :: c
    real(wp), intent(in) :: field(0:, 0:, 0:)
    real(wp) :: u_b(3), u_opposite(3), opposite(3), expected(3)
    integer :: g, m, o
    do g = 1, ibm%geometry%component(c)%n_ghost
      associate (r => ibm%geometry%component(c)%ghost(g))
        if (.not. r%saturated) cycle
        m = r%body
        o = 3 - m
        opposite = r%surface_point + entry_distance(o, r%surface_point, r%normal) * r%normal
        u_b = velocity(:, m) + cross(angular_velocity(:, m), r%surface_point - bodies(m)%centre)
        u_opposite = velocity(:, o) + cross(angular_velocity(:, o), opposite - bodies(o)%centre)
        expected = u_b - r%distance / saturation_gap * (u_opposite - u_b)
        worst_couette = max(worst_couette, abs(field(r%node(1), r%node(2), r%node(3)) - expected(c)))
      end associate
    end do
  end subroutine compare_couette

  !> Random values of the size of the body velocities at every node (halos included).
  subroutine fill_random(field)
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: i, j, k
    do k = 0, grid%nz_local + 1
      do j = 0, grid%ny + 1
        do i = 0, grid%nx + 1
          field(i, j, k) = 2.0e-3_wp * stream_normal(stream)
        end do
      end do
    end do
  end subroutine fill_random

  subroutine zero_ghosts(c, field)
    integer, intent(in) :: c
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: g
    do g = 1, ibm%geometry%component(c)%n_ghost
      associate (node => ibm%geometry%component(c)%ghost(g)%node)
        field(node(1), node(2), node(3)) = 0
      end associate
    end do
  end subroutine zero_ghosts
end program test_immersed_fallback
