! checks: 17
!> Unit tests of quaternion: algebra, rotation matrix, axis-angle and matrix round trips, the
!> kinematic update (exactness, norm drift over 1e6 steps, body-frame convention) and Shoemake's
!> uniform random orientation.
program test_quaternion
  use agglo_kinds, only: wp, i8
  use physical_constants, only: pi
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: quaternion_identity, quaternion_product, quaternion_conjugate, quaternion_normalise, &
                        quaternion_norm, rotation_matrix, rotate_to_lab, rotate_to_body, &
                        quaternion_from_axis_angle, quaternion_to_axis_angle, quaternion_from_matrix, &
                        random_orientation, quaternion_rate, quaternion_advance, symmetry_axis
  use test_framework, only: test_start, test_finish, check_close, check_below
  implicit none
  type(random_stream_t) :: stream
  real(wp) :: q(4), p(4), r(4), v(3), axis(3), axis_back(3), angle, angle_back, omega(3)
  real(wp) :: rot(3,3), eye(3,3), worst, worst_axis, drift, dt, h, skew(3,3), rate_fd(3,3)
  real(wp) :: sum_z2, sum_x2, sum_y2, standard_error, e(3)
  integer :: i, k, n_steps
  integer, parameter :: n_samples = 200000

  call test_start('quaternion')
  call stream_seed(stream, 2024_i8, stream_id=3)
  eye = 0.0_wp
  do i = 1, 3
    eye(i,i) = 1.0_wp
  end do

  ! Algebra: q (x) q* = identity for unit q; the product is associative (Hamilton).
  q = random_unit()
  p = random_unit()
  r = random_unit()
  call check_below(maxval(abs(quaternion_product(q, quaternion_conjugate(q)) - quaternion_identity)), &
                   1.0e-15_wp, 'product_with_conjugate_is_identity')
  call check_below(maxval(abs(quaternion_product(quaternion_product(q, p), r) - &
                              quaternion_product(q, quaternion_product(p, r)))), 1.0e-15_wp, 'product_associative')
  ! i (x) j = k (Hamilton's rule).
  call check_below(maxval(abs(quaternion_product([0.0_wp, 1.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 1.0_wp, 0.0_wp]) &
                              - [0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp])), 0.0_wp, 'hamilton_i_times_j_is_k')

  ! Rotation matrix: orthonormal with det +1, equal to q (x) (0,v) (x) q*, rotate both ways.
  worst = 0.0_wp
  worst_axis = 0.0_wp
  do k = 1, 1000
    q = random_unit()
    rot = rotation_matrix(q)
    worst = max(worst, maxval(abs(matmul(transpose(rot), rot) - eye)), abs(determinant(rot) - 1.0_wp))
    v = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    r = quaternion_product(quaternion_product(q, [0.0_wp, v]), quaternion_conjugate(q))
    worst_axis = max(worst_axis, maxval(abs(r(2:4) - rotate_to_lab(q, v))) / norm2(v), &
                     maxval(abs(rotate_to_body(q, rotate_to_lab(q, v)) - v)) / norm2(v), &
                     maxval(abs(symmetry_axis(q) - rot(:,1))))
  end do
  call check_below(worst, 1.0e-14_wp, 'rotation_matrix_orthonormal_det_one')
  call check_below(worst_axis, 1.0e-14_wp, 'rotation_matrix_equals_sandwich_product')
  ! A quarter turn about z takes body x to lab y.
  q = quaternion_from_axis_angle([0.0_wp, 0.0_wp, 2.0_wp], 0.5_wp*pi)
  call check_below(maxval(abs(rotate_to_lab(q, [1.0_wp, 0.0_wp, 0.0_wp]) - [0.0_wp, 1.0_wp, 0.0_wp])), &
                   1.0e-15_wp, 'quarter_turn_about_z')

  ! Axis-angle round trip (angles in (0, pi], including pi and tiny angles) and matrix round trip.
  worst = 0.0_wp
  worst_axis = 0.0_wp
  do k = 1, 1000
    axis = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    axis = axis / norm2(axis)
    angle = pi * stream_uniform(stream)
    if (k == 1) angle = pi
    if (k == 2) angle = 1.0e-9_wp
    q = quaternion_from_axis_angle(axis, angle)
    call quaternion_to_axis_angle(q, axis_back, angle_back)
    worst = max(worst, abs(angle_back - angle))
    worst_axis = max(worst_axis, norm2(axis_back - axis) * min(1.0_wp, angle / 1.0e-6_wp))
    p = quaternion_from_matrix(rotation_matrix(q))
    ! q and -q are the same rotation.
    worst_axis = max(worst_axis, min(maxval(abs(p - q)), maxval(abs(p + q))))
  end do
  call check_below(worst, 1.0e-14_wp, 'axis_angle_round_trip_angle')
  call check_below(worst_axis, 1.0e-13_wp, 'axis_angle_and_matrix_round_trip_axis')

  ! Kinematic update, constant body angular velocity: the exponential map is exact, so n steps of
  ! dt equal one rotation by |omega| n dt about omega (body axis = lab axis for this rotation).
  omega = [3.0e3_wp, -1.0e3_wp, 2.0e3_wp]
  dt = 2.0e-7_wp
  n_steps = 1000000
  q = quaternion_from_axis_angle([1.0_wp, 2.0_wp, 3.0_wp], 0.7_wp)
  p = q
  drift = 0.0_wp
  do i = 1, n_steps
    p = quaternion_advance(p, omega, dt)
    drift = max(drift, abs(quaternion_norm(p) - 1.0_wp))
  end do
  ! Reference: 1e6 steps at the paper's dt (2e-7 s); docs/physics.md section 0, docs/studies/validation.md: drift <= 1e-12.
  call check_below(drift, 1.0e-12_wp, 'norm_drift_1e6_steps')
  r = quaternion_product(q, quaternion_from_axis_angle(omega, norm2(omega) * dt * n_steps))
  ! 1e6 steps of round-off (~1e-16 each, random walk ~1e-13, worst case linear 1e-10).
  call check_below(min(maxval(abs(p - r)), maxval(abs(p + r))), 1.0e-10_wp, 'exponential_map_exact_for_constant_omega')

  ! Body-frame convention: dR/dt = R [omega_body]x (d/dt of v_lab = R v_body for a fixed body
  ! vector is omega_lab x v_lab with omega_lab = R omega_body). Central difference over +-h.
  q = random_unit()
  omega = [0.3_wp, -1.1_wp, 0.7_wp]
  h = 1.0e-5_wp
  rate_fd = (rotation_matrix(quaternion_advance(q, omega, h)) - rotation_matrix(quaternion_advance(q, omega, -h))) / (2*h)
  skew = reshape([0.0_wp, omega(3), -omega(2), -omega(3), 0.0_wp, omega(1), omega(2), -omega(1), 0.0_wp], [3, 3])
  call check_below(maxval(abs(rate_fd - matmul(rotation_matrix(q), skew))), 1.0e-9_wp, 'body_angular_velocity_convention')
  ! quaternion_rate is the same derivative.
  r = (quaternion_advance(q, omega, h) - quaternion_advance(q, omega, -h)) / (2*h)
  call check_below(maxval(abs(r - quaternion_rate(q, omega))), 1.0e-9_wp, 'quaternion_rate_matches_update')

  ! Shoemake: the symmetry axis p = R(q) e_x is uniform on the sphere, so <p_i^2> = 1/3 with
  ! variance of p_i^2 equal to 1/5 - 1/9 = 4/45 (moments of a uniform unit vector). 4 standard errors.
  sum_x2 = 0; sum_y2 = 0; sum_z2 = 0
  do k = 1, n_samples
    e = symmetry_axis(random_orientation(stream))
    sum_x2 = sum_x2 + e(1)**2
    sum_y2 = sum_y2 + e(2)**2
    sum_z2 = sum_z2 + e(3)**2
  end do
  standard_error = sqrt(4.0_wp / 45.0_wp / n_samples)
  call check_close(sum_z2 / n_samples, 1.0_wp/3.0_wp, 0.0_wp, 'shoemake_mean_pz2_one_third', 4*standard_error)
  call check_close(sum_x2 / n_samples, 1.0_wp/3.0_wp, 0.0_wp, 'shoemake_mean_px2_one_third', 4*standard_error)
  call check_close(sum_y2 / n_samples, 1.0_wp/3.0_wp, 0.0_wp, 'shoemake_mean_py2_one_third', 4*standard_error)
  ! Unit norm of the samples.
  worst = 0.0_wp
  do k = 1, 1000
    worst = max(worst, abs(quaternion_norm(random_orientation(stream)) - 1.0_wp))
  end do
  call check_below(worst, 1.0e-15_wp, 'shoemake_unit_norm')
  ! Normalise: direction kept, length one.
  q = quaternion_normalise([2.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
  call check_below(maxval(abs(q - quaternion_identity)), 0.0_wp, 'normalise')

  call test_finish()

contains

  function random_unit() result(u)
    real(wp) :: u(4)
    u = quaternion_normalise([stream_normal(stream), stream_normal(stream), stream_normal(stream), &
                              stream_normal(stream)])
  end function random_unit

  pure function determinant(m) result(d)
    real(wp), intent(in) :: m(3,3)
    real(wp) :: d
    d = m(1,1)*(m(2,2)*m(3,3) - m(2,3)*m(3,2)) - m(1,2)*(m(2,1)*m(3,3) - m(2,3)*m(3,1)) &
        + m(1,3)*(m(2,1)*m(3,2) - m(2,2)*m(3,1))
  end function determinant

end program test_quaternion
