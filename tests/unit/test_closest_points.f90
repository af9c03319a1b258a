! checks: 25
!> Tests of closest_points: exact cases (spheres; coaxial and laterally offset parallel disks;
!> tip-to-tip, side-by-side and crossed needles; overlaps), >= 1000 random pairs against an
!> independent brute-force reference (dense sampling of body 1's surface, exact point-to-spheroid
!> distance to body 2, local refinement), warm starts, the gap's lower bound without the solve, the
!> failure report, psi and the parametric angles of the closest points.
program test_closest_points
  use agglo_kinds, only: wp, i8
  use physical_constants, only: pi
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: quaternion_product, quaternion_from_axis_angle, rotation_matrix, random_orientation
  use spheroid, only: spheroid_t, make_spheroid, surface_point, implicit_function, support_value
  use closest_points, only: closest_points_t, find_closest_points, symmetry_axis_angle, lab_point_surface_angles, &
                            gap_lower_bound
  use wall_clock, only: wall_time
  use brute_force_distance, only: point_ellipse_distance, brute_force_gap
  use test_framework, only: test_start, test_finish, check, check_close, check_below, check_equal
  implicit none
  real(wp), parameter :: radius = 50.0e-6_wp, density = 2710.0_wp
  type(random_stream_t) :: stream
  type(spheroid_t) :: sphere1, sphere2, needle, needle20, disk, disk20, body1, body2
  type(closest_points_t) :: res, res_warm, res_cold
  real(wp) :: q1(4), q2(4), c1(3), c2(3), u(3), rot(3,3), gap, worst, worst_overlap, reference, t0
  real(wp) :: gaps(6), worst_point, theta, phi
  integer :: k, i

  call test_start('closest_points')
  call stream_seed(stream, 4_i8, stream_id=3)
  sphere1 = make_spheroid('sphere', radius, density)
  sphere2 = make_spheroid('sphere', 0.6_wp * radius, density)
  needle = make_spheroid('needle', radius, density)
  needle20 = make_spheroid('needle', radius, density, 20.0_wp)
  disk = make_spheroid('disk', radius, density)
  disk20 = make_spheroid('disk', radius, density, 20.0_wp)
  gaps = [1.0e-10_wp, 1.0e-9_wp, 1.0e-6_wp, 1.0e-4_wp, -1.0e-9_wp, -1.0e-6_wp]

  ! --- Exact: spheres, gap = |X2 - X1| - r1 - r2 (overlaps included).
  worst = 0.0_wp
  do k = 1, 60
    gap = gaps(mod(k, 6) + 1)
    u = random_unit()
    c1 = 1.0e-3_wp * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
    c2 = c1 + u * (sphere1%radius + sphere2%radius + gap)
    call find_closest_points(sphere1, c1, random_orientation(stream), sphere2, c2, random_orientation(stream), res)
    reference = norm2(c2 - c1) - sphere1%radius - sphere2%radius
    worst = max(worst, abs(res%gap - reference) / radius, merge(0.0_wp, 1.0_wp, res%converged), &
                norm2(res%normal - (c2 - c1) / norm2(c2 - c1)))
  end do
  call check_below(worst, 1.0e-12_wp, 'spheres_exact_gap_incl_overlap')

  ! --- Exact: coaxial parallel disks (faces touching at the poles), arbitrary common orientation,
  ! aspect ratios 1/5 and 1/20, gaps 0.1 nm to 100 um and overlaps: gap = |d| - 2a.
  worst = 0.0_wp
  worst_overlap = 0.0_wp
  do k = 1, 60
    body1 = merge(disk, disk20, mod(k, 2) == 0)
    gap = gaps(mod(k, 6) + 1)
    q1 = random_orientation(stream)
    rot = rotation_matrix(q1)
    c1 = 1.0e-3_wp * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
    c2 = c1 + rot(:,1) * (2 * body1%a + gap)
    call find_closest_points(body1, c1, q1, body1, c2, q1, res)
    if (gap > 0) then
      worst = max(worst, abs(res%gap - gap) / radius, merge(0.0_wp, 1.0_wp, res%converged))
    else
      worst_overlap = max(worst_overlap, abs(res%gap - gap) / radius, merge(0.0_wp, 1.0_wp, res%converged))
    end if
  end do
  call check_below(worst, 1.0e-12_wp, 'parallel_disks_face_to_face_exact_gap')
  call check_below(worst_overlap, 1.0e-12_wp, 'parallel_disks_face_to_face_overlap_depth')

  ! --- Exact: translated copies (parallel disks with lateral offset, near-flat faces facing each other):
  ! E2 = E1 + d, so the Minkowski difference is the spheroid (2a, 2b) and the distance is that of the
  ! point d from it (Eberly's point-to-ellipsoid distance, independent of the method under test).
  worst = 0.0_wp
  do k = 1, 60
    body1 = merge(disk, disk20, mod(k, 2) == 0)
    gap = 10.0_wp ** (-10.0_wp + 6.0_wp * stream_uniform(stream))
    q1 = random_orientation(stream)
    rot = rotation_matrix(q1)
    ! Offset in the body frame: mostly along the axis (faces facing), laterally up to 0.9 b.
    u = [2 * body1%a + gap, 0.9_wp * body1%b * stream_uniform(stream), 0.0_wp]
    call exact_translated_copy(body1, u, gap, reference)
    c1 = [0.3e-3_wp, 0.5e-3_wp, 0.7e-3_wp]
    c2 = c1 + matmul(rot, u)
    call find_closest_points(body1, c1, q1, body1, c2, q1, res)
    worst = max(worst, abs(res%gap - reference) / radius, merge(0.0_wp, 1.0_wp, res%converged))
  end do
  call check_below(worst, 1.0e-11_wp, 'translated_disks_lateral_offset_vs_point_distance')

  ! --- Exact: needles tip-to-tip (|d| - 2a), side by side (|d| - 2b), crossed (|d| - 2b),
  ! aspect ratios 5 and 20, gaps down to 0.1 nm and small overlaps.
  worst = 0.0_wp
  worst_overlap = 0.0_wp
  do k = 1, 90
    body1 = merge(needle, needle20, mod(k, 2) == 0)
    gap = gaps(mod(k, 6) + 1)
    q1 = random_orientation(stream)
    rot = rotation_matrix(q1)
    c1 = 1.0e-3_wp * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
    select case (mod(k / 6, 3))
    case (0)    ! tip to tip
      q2 = q1
      c2 = c1 + rot(:,1) * (2 * body1%a + gap)
      reference = norm2(c2 - c1) - 2 * body1%a
    case (1)    ! side by side, parallel
      q2 = q1
      c2 = c1 + rot(:,2) * (2 * body1%b + gap)
      reference = norm2(c2 - c1) - 2 * body1%b
    case default  ! crossed at right angles, separated along body z
      q2 = quaternion_product(q1, quaternion_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], 0.5_wp * pi))
      c2 = c1 + rot(:,3) * (2 * body1%b + gap)
      reference = norm2(c2 - c1) - 2 * body1%b
    end select
    call find_closest_points(body1, c1, q1, body1, c2, q2, res)
    if (gap > 0) then
      worst = max(worst, abs(res%gap - reference) / radius, merge(0.0_wp, 1.0_wp, res%converged))
    else
      worst_overlap = max(worst_overlap, abs(res%gap - reference) / radius, merge(0.0_wp, 1.0_wp, res%converged))
    end if
  end do
  call check_below(worst, 1.0e-12_wp, 'needles_tip_side_crossed_exact_gap')
  call check_below(worst_overlap, 1.0e-12_wp, 'needles_tip_side_crossed_overlap_depth')

  ! --- Random pairs against brute force (needle-needle, disk-disk, mixed, near-spheres).
  t0 = wall_time()
  call random_pairs_vs_brute_force()
  write(*, '(a,f8.2,a)') '  random pairs incl. brute force: ', wall_time() - t0, ' s'

  ! --- Near-parallel flat faces: aspect-ratio-20 disks face to face, tilted by 1e-7 .. 1e-2 rad,
  ! laterally offset, gaps 0.1 nm .. 1 um, against brute force.
  worst = 0.0_wp
  do k = 1, 40
    q1 = random_orientation(stream)
    rot = rotation_matrix(q1)
    q2 = quaternion_product(q1, quaternion_from_axis_angle([0.0_wp, stream_normal(stream), stream_normal(stream)], &
                                                           10.0_wp ** (-7.0_wp + 5.0_wp * stream_uniform(stream))))
    gap = 10.0_wp ** (-10.0_wp + 4.0_wp * stream_uniform(stream))
    c1 = [0.5e-3_wp, 0.5e-3_wp, 0.5e-3_wp]
    u = rot(:,1) + 0.3_wp * disk20%b / disk20%a * stream_uniform(stream) * rot(:,2)
    u = u / norm2(u)
    c2 = c1 + u * (support_value(disk20, matmul(u, rot)) + support_value(disk20, matmul(-u, rotation_matrix(q2))) + gap)
    call find_closest_points(disk20, c1, q1, disk20, c2, q2, res)
    reference = brute_force_gap(disk20, c1, rot, disk20, c2, rotation_matrix(q2))
    worst = max(worst, abs(res%gap - reference) / radius, merge(0.0_wp, 1.0_wp, res%converged))
  end do
  call check_below(worst, 1.0e-9_wp, 'near_parallel_disk_faces_vs_brute_force')

  ! --- Cold-started overlaps of extreme shapes: a separated pair is pushed along its common normal
  ! by its gap plus depth (0.1 nm .. 0.1 um), so the closest points pass each other and the pair
  ! overlaps with a penetration depth of at most that depth (minimum translation distance).
  ! Expected: converged, gap in [-depth, 0).
  worst = 0.0_wp
  do k = 1, 400
    body1 = merge(needle20, disk20, mod(k, 2) == 0)
    body2 = merge(needle20, disk20, mod(k / 2, 2) == 0)
    gap = -10.0_wp ** (-10.0_wp + 3.0_wp * stream_uniform(stream))
    q1 = random_orientation(stream)
    q2 = random_orientation(stream)
    u = random_unit()
    c1 = 0.0_wp
    c2 = u * (support_value(body1, matmul(u, rotation_matrix(q1))) + support_value(body2, matmul(-u, rotation_matrix(q2))) &
              + 1.0e-6_wp)
    call find_closest_points(body1, c1, q1, body2, c2, q2, res)
    c2 = c2 - (res%gap - gap) * res%normal
    call find_closest_points(body1, c1, q1, body2, c2, q2, res)
    if (.not. res%converged .or. res%gap >= 0.0_wp .or. res%gap < gap - 1.0e-12_wp * radius) then
      worst = max(worst, 1.0_wp)
      write(*, '(a,i0,2es12.4,1x,a)') '  overlap case ', k, gap, res%gap, trim(res%message)
    end if
  end do
  call check_below(worst, 0.0_wp, 'cold_started_overlaps_extreme_shapes')

  ! --- Warm start: after a small relative motion the previous normal converges in <= 3 iterations.
  c1 = [0.0_wp, 0.0_wp, 0.0_wp]
  q1 = random_orientation(stream)
  q2 = random_orientation(stream)
  u = random_unit()
  c2 = u * (support_value(needle20, matmul(u, rotation_matrix(q1))) + &
            support_value(needle20, matmul(-u, rotation_matrix(q2))) + 2.0e-6_wp)
  call find_closest_points(needle20, c1, q1, needle20, c2, q2, res)
  q2 = quaternion_product(q2, quaternion_from_axis_angle([0.3_wp, 1.0_wp, -0.2_wp], 2.0e-4_wp))
  c2 = c2 - 1.0e-8_wp * res%normal
  call find_closest_points(needle20, c1, q1, needle20, c2, q2, res_warm, previous=res)
  call find_closest_points(needle20, c1, q1, needle20, c2, q2, res_cold)
  call check(res_warm%converged .and. res_warm%iterations <= 3, 'warm_start_converges_in_3_iterations', &
             'warm '//itoa(res_warm%iterations)//' cold '//itoa(res_cold%iterations)//' iterations')
  call check_below(abs(res_warm%gap - res_cold%gap) / radius, 1.0e-13_wp, 'warm_and_cold_start_agree')

  ! Overlap reached from a separated state keeps its branch (warm start) and reports the depth.
  c1 = 0.0_wp
  q1 = random_orientation(stream)
  rot = rotation_matrix(q1)
  c2 = rot(:,1) * (2 * needle20%a + 1.0e-9_wp)
  call find_closest_points(needle20, c1, q1, needle20, c2, q1, res)
  c2 = rot(:,1) * (2 * needle20%a - 5.0e-9_wp)
  call find_closest_points(needle20, c1, q1, needle20, c2, q1, res_warm, previous=res)
  call check_close(res_warm%gap, -5.0e-9_wp, 1.0e-6_wp, 'warm_started_overlap_depth_tip_to_tip')

  ! --- Failure report: no iterations allowed from a generic configuration -> not converged, message.
  c2 = [3.1e-4_wp, 0.7e-4_wp, -0.4e-4_wp]
  call find_closest_points(needle20, c1, random_orientation(stream), disk20, c2, random_orientation(stream), res, &
                           max_iterations=0)
  call check(.not. res%converged .and. len_trim(res%message) > 0 .and. abs(res%gap) < 1.0_wp, &
             'failure_reported_not_silent', trim(res%message))

  ! --- psi: equal axes 0, perpendicular pi/2, antiparallel 0 (axes are lines), range [0, pi/2].
  q1 = random_orientation(stream)
  call check_below(symmetry_axis_angle(q1, q1), 1.0e-7_wp, 'psi_equal_orientation_zero')
  q2 = quaternion_product(q1, quaternion_from_axis_angle([0.0_wp, 1.0_wp, 0.0_wp], 0.5_wp * pi))
  call check_close(symmetry_axis_angle(q1, q2), 0.5_wp * pi, 1.0e-14_wp, 'psi_perpendicular_half_pi')
  q2 = quaternion_product(q1, quaternion_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], pi))
  call check_below(symmetry_axis_angle(q1, q2), 1.0e-7_wp, 'psi_antiparallel_zero')
  q2 = quaternion_product(q1, quaternion_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], 2.0_wp))
  call check_close(symmetry_axis_angle(q1, q2), pi - 2.0_wp, 1.0e-13_wp, 'psi_obtuse_folded')

  ! --- Collision-point angles: (theta1, phi1) of the result map back to point1; the lab-point routine
  ! agrees; needle tip-to-tip contact is at the poles phi = 0 / pi.
  worst_point = 0.0_wp
  do i = 1, 50
    q1 = random_orientation(stream)
    q2 = random_orientation(stream)
    u = random_unit()
    c1 = [1.0e-4_wp, 2.0e-4_wp, 3.0e-4_wp]
    c2 = c1 + u * (support_value(needle, matmul(u, rotation_matrix(q1))) + &
                   support_value(disk, matmul(-u, rotation_matrix(q2))) + 1.0e-7_wp)
    call find_closest_points(needle, c1, q1, disk, c2, q2, res)
    worst_point = max(worst_point, &
      norm2(c1 + matmul(rotation_matrix(q1), surface_point(needle, res%theta1, res%phi1)) - res%point1) / radius, &
      norm2(c2 + matmul(rotation_matrix(q2), surface_point(disk, res%theta2, res%phi2)) - res%point2) / radius)
    call lab_point_surface_angles(needle, c1, q1, res%point1, theta, phi)
    worst_point = max(worst_point, abs(theta - res%theta1) + abs(phi - res%phi1))
  end do
  call check_below(worst_point, 1.0e-12_wp, 'closest_point_angles_round_trip')
  q1 = random_orientation(stream)
  rot = rotation_matrix(q1)
  call find_closest_points(needle, c1, q1, needle, c1 + rot(:,1) * (2 * needle%a + 1.0e-8_wp), q1, res)
  call check_below(abs(res%phi1) + abs(abs(res%phi2) - pi), 1.0e-6_wp, 'tip_to_tip_contact_at_poles')

  call test_finish()

contains

  function random_unit() result(v)
    real(wp) :: v(3)
    v = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    v = v / norm2(v)
  end function random_unit

  function itoa(i) result(text)
    integer, intent(in) :: i
    character(len=12) :: text
    write(text, '(i0)') i
  end function itoa

  !> E1 and E2 = E1 + d (same orientation): distance = distance of the body-frame point d from the
  !> spheroid with semi-axes (2a, 2b) (the Minkowski difference E2 - E1 shifted), minus nothing.
  subroutine exact_translated_copy(body, offset_body, gap_hint, distance)
    type(spheroid_t), intent(in) :: body
    real(wp), intent(in) :: offset_body(3), gap_hint
    real(wp), intent(out) :: distance
    distance = point_ellipse_distance(2 * body%a, 2 * body%b, abs(offset_body(1)), norm2(offset_body(2:3)))
    if (gap_hint < 0) distance = -distance
  end subroutine exact_translated_copy

  subroutine random_pairs_vs_brute_force()
    integer, parameter :: n_pairs = 1200
    integer :: k, kind, n_converged, max_iterations, total_iterations, n_fallback, it
    real(wp) :: worst_error, error, target, brute, worst_consistency, ratio, worst_bound, smallest_gap, largest_gap
    real(wp) :: worst_cold_bound, worst_warm_bound
    character(len=16) :: name1, name2
    character(len=200) :: detail
    worst_error = 0; worst_consistency = 0; worst_bound = 0; worst_cold_bound = -huge(1.0_wp); worst_warm_bound = 0
    n_converged = 0; max_iterations = 0; total_iterations = 0; n_fallback = 0
    smallest_gap = huge(1.0_wp); largest_gap = 0
    do k = 1, n_pairs
      kind = mod(k, 4)
      ratio = 10.0_wp ** (log10(20.0_wp) * stream_uniform(stream))
      if (mod(k, 16) == 1) ratio = 20.0_wp
      if (mod(k, 16) == 2) ratio = 1.0001_wp
      if (mod(k, 16) == 3) ratio = 1.0_wp
      select case (kind)
      case (0); name1 = 'needle'; name2 = 'needle'
      case (1); name1 = 'disk'; name2 = 'disk'
      case (2); name1 = 'needle'; name2 = 'disk'
      case default; name1 = 'disk'; name2 = 'needle'
      end select
      body1 = make_spheroid(name1, radius, density, ratio)
      body2 = make_spheroid(name2, radius * (0.5_wp + stream_uniform(stream)), density, &
                            10.0_wp ** (log10(20.0_wp) * stream_uniform(stream)))
      target = 10.0_wp ** (-9.0_wp + 5.0_wp * stream_uniform(stream))     ! 1 nm .. 100 um
      if (mod(k, 50) == 0) target = 1.0e-10_wp                             ! extreme: 0.1 nm
      q1 = random_orientation(stream)
      q2 = random_orientation(stream)
      u = random_unit()
      c1 = 1.0e-3_wp * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
      c2 = c1 + u * (support_value(body1, matmul(u, rotation_matrix(q1))) + &
                     support_value(body2, matmul(-u, rotation_matrix(q2))) + target)
      call find_closest_points(body1, c1, q1, body2, c2, q2, res)
      ! Move body 2 along the common normal towards the target gap (the first placement only
      ! guarantees gap >= target); two corrections bring it close.
      do it = 1, 2
        c2 = c2 + (target - res%gap) * res%normal
        call find_closest_points(body1, c1, q1, body2, c2, q2, res)
      end do
      if (res%converged) n_converged = n_converged + 1
      if (res%starts > 1) n_fallback = n_fallback + 1
      max_iterations = max(max_iterations, res%iterations)
      total_iterations = total_iterations + res%iterations
      smallest_gap = min(smallest_gap, res%gap)
      largest_gap = max(largest_gap, res%gap)
      brute = brute_force_gap(body1, c1, rotation_matrix(q1), body2, c2, rotation_matrix(q2))
      error = abs(brute - res%gap) / radius
      if (error > worst_error) then
        worst_error = error
        write(detail, '(a,i0,1x,a,a,a,f8.3,a,es12.5,a,es12.5)') 'pair ', k, trim(name1), '-', trim(name2), ratio, &
          ' gap ', res%gap, ' brute ', brute
      end if
      ! The points: on the surfaces, and point2 - point1 = gap normal up to the residual.
      worst_consistency = max(worst_consistency, &
        abs(implicit_function(body1, matmul(res%point1 - c1, rotation_matrix(q1)))), &
        abs(implicit_function(body2, matmul(res%point2 - c2, rotation_matrix(q2)))), &
        ! the convergence criterion bounds this by 1e-12 of the smaller radius
        norm2(res%point2 - res%point1 - res%gap * res%normal) / min(body1%radius, body2%radius))
      worst_bound = max(worst_bound, res%distance_bound / radius)
      ! The gap's lower bound without the solve (gap_lower_bound, the slab gap G): from the centre
      ! line alone at most the gap; at the converged normal the gap itself (G(n*) = h).
      worst_cold_bound = max(worst_cold_bound, &
                             (gap_lower_bound(body1, c1, q1, body2, c2, q2, closest_points_t()) - res%gap) / radius)
      worst_warm_bound = max(worst_warm_bound, abs(gap_lower_bound(body1, c1, q1, body2, c2, q2, res) - res%gap) / radius)
    end do
    call check_below(worst_cold_bound, 1.0e-12_wp, 'lower_bound_from_centre_line_below_gap')
    call check_below(worst_warm_bound, 1.0e-12_wp, 'lower_bound_at_common_normal_is_gap')
    write(*, '(a,i0,a,i0,a,f5.2,a,i0,a,es10.3,a,es10.3,a)') '  random pairs: ', n_pairs, ' converged ', n_converged, &
      ', mean iterations ', real(total_iterations, wp) / n_pairs, ', max ', max_iterations, ', gaps ', smallest_gap, &
      ' .. ', largest_gap, ' m'
    write(*, '(a,es10.3,a,es10.3,a,i0)') '  worst |gap - brute| / r = ', worst_error, ', worst certificate bound / r = ', &
      worst_bound, ', multi-start fallbacks ', n_fallback
    call check_equal(n_converged, n_pairs, 'random_pairs_all_converged')
    ! Required (docs/studies/validation.md, closest points): gap error <= 1e-9 r against brute force for >= 1000 random pairs.
    call check_below(worst_error, 1.0e-9_wp, 'random_pairs_gap_vs_brute_force  '//trim(detail))
    call check_below(worst_consistency, 1.01e-12_wp, 'random_pairs_points_on_surfaces_and_aligned')
    ! The certified bracket [gap, gap + bound] of the true distance is tight.
    call check_below(worst_bound, 1.0e-12_wp, 'random_pairs_distance_certificate')
    call check(smallest_gap < 2.0e-10_wp .and. largest_gap > 5.0e-5_wp, 'random_pairs_span_0.1nm_to_100um')
  end subroutine random_pairs_vs_brute_force


end program test_closest_points
