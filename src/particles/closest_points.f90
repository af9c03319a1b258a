!> Closest points of two spheroids by the common-normal condition (docs/physics.md section 6; the problem
!> of Jain, Tschisgale & Froehlich, Int. J. Multiph. Flow 120, 103087 (2019), corrigendum 2022):
!> points x1, x2 on the two surfaces whose outward normals are opposite, n1 = -n2 = n, and whose
!> difference is parallel to them, x2 - x1 = h n. h is the signed surface gap (negative = overlap).
!>
!> Method (pole-free; derivation in docs/theory.md, "Particle geometry and closest points"):
!> the unknown is the unit common normal n itself, not surface parameters. With M_i = R_i S_i^2 R_i^T
!> (S_i = diag(a_i, b_i, b_i)), the support function of body i is h_i(n) = sqrt(n^T M_i n) and its
!> support point (the surface point with outward normal n) is X_i + M_i n / h_i(n). The slab gap
!>     G(n) = n.(X2 - X1) - h_1(n) - h_2(-n)
!> is the distance between the two support planes normal to n. For convex bodies the signed distance
!> is the maximum of G over unit n (separating-plane theorem; it is minus the penetration depth when
!> the bodies overlap), and the stationarity condition of G on the sphere is exactly the common-normal
!> condition: grad G = x2 - x1 projected onto the tangent plane of n. G is maximised by a damped
!> Newton (trust-region) iteration on the sphere with the analytic Hessian, whose tangential part is
!> minus the sum of the principal radii-of-curvature tensors at x1 and x2 plus -G: it is negative
!> definite at every separated configuration, so the maximum is well conditioned, and because G is
!> stationary there the gap error is quadratic in the error of n.
!> Robustness: no parametric poles (needle tips and disk faces are ordinary points); a superlevel set
!> {G >= c > 0} is geodesically convex, so for separated bodies a local maximum with G > 0 is the
!> global one; G is a lower bound and |x2 - x1| an upper bound of the true distance for any n, which
!> certifies the result; branch checks; warm start from the previous normal; multi-start fallback;
!> an explicit failure report (converged = .false. and a message) instead of a silent wrong answer.
module closest_points
  use agglo_kinds, only: wp
  use vector_algebra, only: outer, cross
  use quaternion, only: rotation_matrix, symmetry_axis
  use spheroid, only: spheroid_t, surface_angles, implicit_function, normal_at_point
  implicit none
  private
  public :: closest_points_t, find_closest_points, symmetry_axis_angle, lab_point_surface_angles, &
            closest_points_relative_tolerance, gap_lower_bound

  !> Convergence: tangential mismatch |(I - n n^T)(x2 - x1)| below this times the smaller radius
  !> (the gap error is then ~ (1e-12 r)^2 / (radii of curvature), far below round-off).
  real(wp), parameter :: closest_points_relative_tolerance = 1.0e-12_wp
  integer, parameter :: default_max_iterations = 60

  type :: closest_points_t
    real(wp) :: gap = huge(1.0_wp)       !< m, signed surface gap along the common normal (< 0: overlap)
    real(wp) :: point1(3) = 0.0_wp       !< m, lab frame: closest point on body 1
    real(wp) :: point2(3) = 0.0_wp       !< m, lab frame: closest point on body 2
    real(wp) :: normal(3) = 0.0_wp       !< unit common normal from body 1 to body 2 (outward on body 1 at
                                         !< point1, inward on body 2 at point2); point2 - point1 = gap normal
    real(wp) :: theta1 = 0.0_wp, phi1 = 0.0_wp   !< parametric angles of point1 on the unrotated body 1
    real(wp) :: theta2 = 0.0_wp, phi2 = 0.0_wp   !< parametric angles of point2 on the unrotated body 2
    real(wp) :: residual = 0.0_wp        !< m, tangential mismatch |(I - n n^T)(point2 - point1)|
    real(wp) :: distance_bound = 0.0_wp  !< m, |point2 - point1| - gap >= 0 for separated pairs: the true
                                         !< distance lies in [gap, gap + distance_bound]
    integer :: iterations = 0            !< Newton iterations, all starts together
    integer :: starts = 0                !< starting normals tried (1 when the first start succeeded)
    logical :: converged = .false.
    character(len=256) :: message = ''   !< why it failed (empty when converged)
  end type closest_points_t

  interface find_closest_points
    module procedure closest_points_quaternions, closest_points_matrices
  end interface find_closest_points

contains

  !> Closest points with orientations given as unit quaternions (body -> lab). previous: the result
  !> of the last call for this pair (warm start from its normal when it converged).
  subroutine closest_points_quaternions(body1, centre1, orientation1, body2, centre2, orientation2, result, &
                                        previous, max_iterations)
    type(spheroid_t), intent(in) :: body1, body2
    real(wp), intent(in) :: centre1(3), orientation1(4), centre2(3), orientation2(4)
    type(closest_points_t), intent(out) :: result
    type(closest_points_t), intent(in), optional :: previous
    integer, intent(in), optional :: max_iterations
    call closest_points_matrices(body1, centre1, rotation_matrix(orientation1), body2, centre2, &
                                 rotation_matrix(orientation2), result, previous, max_iterations)
  end subroutine closest_points_quaternions

  !> Closest points with orientations given as rotation matrices (body -> lab, orthonormal).
  subroutine closest_points_matrices(body1, centre1, rotation1, body2, centre2, rotation2, result, &
                                     previous, max_iterations)
    type(spheroid_t), intent(in) :: body1, body2
    real(wp), intent(in) :: centre1(3), rotation1(3,3), centre2(3), rotation2(3,3)
    type(closest_points_t), intent(out) :: result
    type(closest_points_t), intent(in), optional :: previous
    integer, intent(in), optional :: max_iterations
    real(wp) :: form1(3,3), form2(3,3), separation(3), scale, tolerance, normal(3), gap, residual
    real(wp) :: best_normal(3), best_gap, best_residual, starts(3, 40)
    integer :: n_starts, k, iterations, limit
    logical :: ok, have_best, warm
    character(len=160) :: reason, first_reason

    limit = default_max_iterations
    if (present(max_iterations)) limit = max_iterations
    form1 = quadratic_form(body1, rotation1)
    form2 = quadratic_form(body2, rotation2)
    separation = centre2 - centre1
    scale = min(body1%radius, body2%radius)
    ! Round-off floor: x2 - x1 is formed from vectors of length ~|X2 - X1|.
    tolerance = max(closest_points_relative_tolerance * scale, 64.0_wp * epsilon(1.0_wp) * norm2(separation))

    warm = .false.
    if (present(previous)) warm = previous%converged .and. norm2(previous%normal) > 0.5_wp
    call list_starts(separation, rotation1, rotation2, previous, warm, starts, n_starts)

    have_best = .false.
    best_gap = -huge(1.0_wp)
    best_residual = huge(1.0_wp)
    best_normal = starts(:, 1)
    first_reason = ''
    result%iterations = 0
    do k = 1, n_starts
      call maximise_slab_gap(form1, form2, separation, starts(:, k), tolerance, limit, normal, gap, residual, &
                             iterations, ok, reason)
      result%iterations = result%iterations + iterations
      result%starts = k
      if (ok) call check_branch(body1, centre1, rotation1, body2, centre2, rotation2, form1, form2, normal, &
                                gap, ok, reason)
      if (k == 1) first_reason = reason
      if (ok) then
        if (.not. have_best .or. gap > best_gap) then
          best_gap = gap
          best_normal = normal
          best_residual = residual
        end if
        have_best = .true.
        ! A separated pair has a single maximum with G > 0 (see the module header); an overlapping pair
        ! followed from a converged previous step keeps its branch (penetration along the normal it
        ! came in with). Only a cold-started overlap searches all starts for the smallest penetration.
        if (gap >= 0.0_wp .or. (warm .and. k == 1)) exit
      else if (.not. have_best .and. gap > best_gap) then
        best_gap = gap
        best_normal = normal
        best_residual = residual
      end if
    end do

    call fill_result(body1, centre1, rotation1, body2, centre2, rotation2, form1, form2, best_normal, result)
    result%converged = have_best
    if (have_best) then
      result%message = ''
    else
      write(result%message, '(a,i0,a,es10.3,a,es10.3,a)') 'closest_points: no common normal found from ', &
        n_starts, ' starts (best gap estimate ', result%gap, ' m, tangential residual ', result%residual, &
        ' m); first start: '
      result%message = trim(result%message)//' '//trim(first_reason)
    end if
  end subroutine closest_points_matrices

  !> A lower bound (m) of the signed surface gap of two spheroids, without the Newton solve: the
  !> slab gap G(n) = n.(X2 - X1) - h_1(n) - h_2(n) (module header) is at most the signed distance
  !> for every unit n (separating-plane theorem), so the larger of G at the last common normal
  !> (when previous converged) and at the centre line bounds the gap from below. A spheroid's
  !> support function along a unit n is h(n) = sqrt(b^2 + (a^2 - b^2) (n.e)^2), e its symmetry axis.
  pure function gap_lower_bound(body1, centre1, orientation1, body2, centre2, orientation2, previous) result(bound)
    type(spheroid_t), intent(in) :: body1, body2
    real(wp), intent(in) :: centre1(3), orientation1(4), centre2(3), orientation2(4)
    type(closest_points_t), intent(in) :: previous
    real(wp) :: bound
    real(wp) :: separation(3), axis1(3), axis2(3), distance
    separation = centre2 - centre1
    axis1 = symmetry_axis(orientation1)
    axis2 = symmetry_axis(orientation2)
    bound = -huge(1.0_wp)
    distance = norm2(separation)
    if (distance > 0.0_wp) bound = slab_gap_along(separation / distance)
    if (previous%converged .and. norm2(previous%normal) > 0.5_wp) &
      bound = max(bound, slab_gap_along(previous%normal / norm2(previous%normal)))
  contains
    pure real(wp) function slab_gap_along(normal)
      real(wp), intent(in) :: normal(3)
      slab_gap_along = dot_product(separation, normal) &
          - sqrt(body1%b**2 + (body1%a**2 - body1%b**2) * dot_product(normal, axis1)**2) &
          - sqrt(body2%b**2 + (body2%a**2 - body2%b**2) * dot_product(normal, axis2)**2)
    end function slab_gap_along
  end function gap_lower_bound

  !> M = R S^2 R^T: the support function of the rotated spheroid is sqrt(n^T M n).
  pure function quadratic_form(body, rotation) result(form)
    type(spheroid_t), intent(in) :: body
    real(wp), intent(in) :: rotation(3,3)
    real(wp) :: form(3,3)
    integer :: i, j
    do j = 1, 3
      do i = 1, 3
        form(i,j) = body%a**2 * rotation(i,1) * rotation(j,1) &
                  + body%b**2 * (rotation(i,2) * rotation(j,2) + rotation(i,3) * rotation(j,3))
      end do
    end do
  end function quadratic_form

  !> Starting normals: the warm start (previous normal), the centre line (cold start), then the
  !> multi-start fallbacks, tried only when the earlier starts fail: both symmetry axes with both
  !> signs and the 26 directions of a 3x3x3 stencil (every octant, edge and face direction).
  subroutine list_starts(separation, rotation1, rotation2, previous, warm, starts, n_starts)
    real(wp), intent(in) :: separation(3), rotation1(3,3), rotation2(3,3)
    type(closest_points_t), intent(in), optional :: previous
    logical, intent(in) :: warm
    real(wp), intent(out) :: starts(3, 40)
    integer, intent(out) :: n_starts
    integer :: i, j, k
    n_starts = 0
    if (warm) call add(previous%normal)
    if (norm2(separation) > 0.0_wp) then
      call add(separation)
    else
      call add([1.0_wp, 0.0_wp, 0.0_wp])
    end if
    call add(rotation1(:,1)); call add(-rotation1(:,1))
    call add(rotation2(:,1)); call add(-rotation2(:,1))
    do k = -1, 1
      do j = -1, 1
        do i = -1, 1
          if (i /= 0 .or. j /= 0 .or. k /= 0) call add(real([i, j, k], wp))
        end do
      end do
    end do
  contains
    subroutine add(v)
      real(wp), intent(in) :: v(3)
      if (n_starts >= size(starts, 2)) return
      n_starts = n_starts + 1
      starts(:, n_starts) = v / norm2(v)
    end subroutine add
  end subroutine list_starts

  !> Slab gap G(n), the support offsets y_i = M_i n / h_i(n) and the gradient x2 - x1 = d - y1 - y2
  !> (the unconstrained gradient of G extended as a 1-homogeneous function).
  pure subroutine slab_gap(form1, form2, separation, normal, gap, offset1, offset2, support1, support2)
    real(wp), intent(in) :: form1(3,3), form2(3,3), separation(3), normal(3)
    real(wp), intent(out) :: gap, offset1(3), offset2(3), support1, support2
    offset1 = matmul(form1, normal)
    offset2 = matmul(form2, normal)
    support1 = sqrt(dot_product(normal, offset1))
    support2 = sqrt(dot_product(normal, offset2))
    offset1 = offset1 / support1
    offset2 = offset2 / support2
    gap = dot_product(separation, normal) - support1 - support2
  end subroutine slab_gap

  !> Damped Newton ascent of G on the unit sphere from start. ok = converged to a local maximum
  !> (tangential gradient below tolerance and negative definite tangential Hessian).
  subroutine maximise_slab_gap(form1, form2, separation, start, tolerance, max_iterations, normal, gap, &
                               residual, iterations, ok, reason)
    real(wp), intent(in) :: form1(3,3), form2(3,3), separation(3), start(3), tolerance
    integer, intent(in) :: max_iterations
    real(wp), intent(out) :: normal(3), gap, residual
    integer, intent(out) :: iterations
    logical, intent(out) :: ok
    character(len=*), intent(out) :: reason
    real(wp) :: offset1(3), offset2(3), support1, support2, gradient(3), tangent1(3), tangent2(3)
    real(wp) :: curvature(3,3), a(2,2), g(2), step(2), step_length, radius, trial(3), trial_gap
    real(wp) :: t_offset1(3), t_offset2(3), t_support1, t_support2, lambda_min, lambda_max, shift, det
    real(wp) :: roundoff, direction(3)
    integer :: i, j
    logical :: definite

    normal = start / norm2(start)
    radius = 0.5_wp                      ! trust radius on the sphere (rad)
    ok = .false.
    reason = 'iteration limit reached'
    call slab_gap(form1, form2, separation, normal, gap, offset1, offset2, support1, support2)
    do iterations = 0, max_iterations
      gradient = separation - offset1 - offset2
      gradient = gradient - dot_product(gradient, normal) * normal
      residual = norm2(gradient)
      call tangent_basis(normal, tangent1, tangent2)
      ! -Hessian of the 1-homogeneous extension: sum over bodies of (M - y y^T)/h (positive
      ! semi-definite; on the tangent plane it is the tensor of principal radii of curvature).
      curvature = (form1 - outer(offset1, offset1)) / support1 + (form2 - outer(offset2, offset2)) / support2
      ! Riemannian -Hessian on the sphere: tangential part of the above plus G times identity.
      a(1,1) = dot_product(tangent1, matmul(curvature, tangent1)) + gap
      a(2,2) = dot_product(tangent2, matmul(curvature, tangent2)) + gap
      a(1,2) = dot_product(tangent1, matmul(curvature, tangent2))
      a(2,1) = a(1,2)
      g = [dot_product(tangent1, gradient), dot_product(tangent2, gradient)]
      call symmetric_eigenvalues(a, lambda_min, lambda_max)
      definite = lambda_min > 1.0e-12_wp * max(lambda_max, tolerance)
      if (residual <= tolerance .and. definite) then
        ok = .true.
        reason = ''
        return
      end if
      if (iterations == max_iterations) exit
      ! Levenberg-Marquardt shift where the quadratic model is not concave (far from the maximum).
      shift = 0.0_wp
      if (.not. definite) shift = max(0.0_wp, -lambda_min) + 1.0e-3_wp * max(abs(lambda_max), residual, tolerance)
      do i = 1, 2
        a(i,i) = a(i,i) + shift
      end do
      det = a(1,1) * a(2,2) - a(1,2)**2
      step = [a(2,2) * g(1) - a(1,2) * g(2), a(1,1) * g(2) - a(1,2) * g(1)] / det
      roundoff = 16.0_wp * epsilon(1.0_wp) * (abs(dot_product(separation, normal)) + support1 + support2)
      do j = 1, 60
        step_length = norm2(step)
        if (step_length > radius) then
          step = step * (radius / step_length)
          step_length = radius
        end if
        if (step_length == 0.0_wp) exit
        direction = (step(1) * tangent1 + step(2) * tangent2) / step_length
        trial = cos(step_length) * normal + sin(step_length) * direction
        trial = trial / norm2(trial)
        call slab_gap(form1, form2, separation, trial, trial_gap, t_offset1, t_offset2, t_support1, t_support2)
        if (trial_gap >= gap - roundoff) exit
        radius = 0.25_wp * step_length
      end do
      if (j > 60 .or. step_length == 0.0_wp) then
        reason = 'no ascent step found (trust region collapsed)'
        exit
      end if
      if (step_length >= 0.99_wp * radius) radius = min(2.0_wp * radius, 1.5_wp)
      normal = trial
      gap = trial_gap
      offset1 = t_offset1; offset2 = t_offset2
      support1 = t_support1; support2 = t_support2
    end do
    if (reason == 'iteration limit reached' .and. residual <= tolerance) &
      reason = 'stationary point is not a maximum (minimum-distance branch not found)'
  end subroutine maximise_slab_gap

  !> Branch and consistency checks of a converged maximum:
  !> separated (G >= 0): n.(X2 - X1) > 0 (the separating plane lies between the centres) and the
  !> surface normals at the closest points are n1.n = +1, n2.n = -1 (n1.d^ = +1, n2.d^ = -1);
  !> overlapping (G < 0): each closest point lies inside the other body (a penetration, not a
  !> spurious maximum of G on the far side of a separated pair).
  subroutine check_branch(body1, centre1, rotation1, body2, centre2, rotation2, form1, form2, normal, gap, &
                          ok, reason)
    type(spheroid_t), intent(in) :: body1, body2
    real(wp), intent(in) :: centre1(3), rotation1(3,3), centre2(3), rotation2(3,3), form1(3,3), form2(3,3)
    real(wp), intent(in) :: normal(3), gap
    logical, intent(out) :: ok
    character(len=*), intent(out) :: reason
    real(wp) :: offset1(3), offset2(3), support1, support2, slab, body_point1(3), body_point2(3), n1(3), n2(3)
    call slab_gap(form1, form2, centre2 - centre1, normal, slab, offset1, offset2, support1, support2)
    body_point1 = matmul(offset1, rotation1)                              ! R1^T (x1 - X1)
    body_point2 = matmul(-offset2, rotation2)                             ! R2^T (x2 - X2)
    n1 = matmul(rotation1, normal_at_point(body1, body_point1))
    n2 = matmul(rotation2, normal_at_point(body2, body_point2))
    ok = .true.
    reason = ''
    if (dot_product(n1, normal) < 1.0_wp - 1.0e-9_wp .or. dot_product(n2, normal) > -1.0_wp + 1.0e-9_wp) then
      ok = .false.
      reason = 'surface normals at the closest points are not opposite (n1.n /= 1 or n2.n /= -1)'
    else if (gap >= 0.0_wp) then
      if (dot_product(centre2 - centre1, normal) <= 0.0_wp) then
        ok = .false.
        reason = 'separated pair with the normal pointing from body 2 to body 1 (wrong branch)'
      end if
    else
      ! x1 in the frame of body 2 and x2 in the frame of body 1.
      if (implicit_function(body2, matmul(centre1 + offset1 - centre2, rotation2)) > 1.0e-9_wp .or. &
          implicit_function(body1, matmul(centre2 - offset2 - centre1, rotation1)) > 1.0e-9_wp) then
        ok = .false.
        reason = 'negative slab gap but the closest points are not inside the other body (spurious branch)'
      end if
    end if
  end subroutine check_branch

  subroutine fill_result(body1, centre1, rotation1, body2, centre2, rotation2, form1, form2, normal, result)
    type(spheroid_t), intent(in) :: body1, body2
    real(wp), intent(in) :: centre1(3), rotation1(3,3), centre2(3), rotation2(3,3), form1(3,3), form2(3,3)
    real(wp), intent(in) :: normal(3)
    type(closest_points_t), intent(inout) :: result
    real(wp) :: offset1(3), offset2(3), support1, support2, gap, difference(3)
    call slab_gap(form1, form2, centre2 - centre1, normal, gap, offset1, offset2, support1, support2)
    result%gap = gap
    result%normal = normal
    result%point1 = centre1 + offset1
    result%point2 = centre2 - offset2
    difference = (centre2 - centre1) - offset1 - offset2
    result%residual = norm2(difference - dot_product(difference, normal) * normal)
    result%distance_bound = norm2(difference) - abs(gap)
    call surface_angles(body1, matmul(offset1, rotation1), result%theta1, result%phi1)
    call surface_angles(body2, matmul(-offset2, rotation2), result%theta2, result%phi2)
  end subroutine fill_result

  !> Angle psi in [0, pi/2] between the symmetry axes of two bodies (orientation quaternions body -> lab);
  !> the axes are lines, so psi and pi - psi are the same configuration. atan2 keeps accuracy near 0.
  pure function symmetry_axis_angle(orientation1, orientation2) result(psi)
    real(wp), intent(in) :: orientation1(4), orientation2(4)
    real(wp) :: psi, e1(3), e2(3)
    e1 = symmetry_axis(orientation1)
    e2 = symmetry_axis(orientation2)
    psi = atan2(norm2(cross(e1, e2)), abs(dot_product(e1, e2)))
  end function symmetry_axis_angle

  !> Parametric angles (theta, phi) on the unrotated body of a lab-frame point on its surface
  !> (e.g. a collision point): the point is taken to the body frame, R^T (x - X), and inverted.
  pure subroutine lab_point_surface_angles(body, centre, orientation, point, theta, phi)
    type(spheroid_t), intent(in) :: body
    real(wp), intent(in) :: centre(3), orientation(4), point(3)
    real(wp), intent(out) :: theta, phi
    call surface_angles(body, matmul(point - centre, rotation_matrix(orientation)), theta, phi)
  end subroutine lab_point_surface_angles

  !> Orthonormal tangent basis of the plane normal to the unit vector n (pole-free: built from the
  !> coordinate axis least aligned with n).
  pure subroutine tangent_basis(n, t1, t2)
    real(wp), intent(in) :: n(3)
    real(wp), intent(out) :: t1(3), t2(3)
    real(wp) :: axis(3)
    axis = 0.0_wp
    axis(minloc(abs(n), 1)) = 1.0_wp
    t1 = cross(n, axis)
    t1 = t1 / norm2(t1)
    t2 = cross(n, t1)
  end subroutine tangent_basis

  !> Eigenvalues of a symmetric 2x2 matrix.
  pure subroutine symmetric_eigenvalues(a, lambda_min, lambda_max)
    real(wp), intent(in) :: a(2,2)
    real(wp), intent(out) :: lambda_min, lambda_max
    real(wp) :: mean, half_difference
    mean = 0.5_wp * (a(1,1) + a(2,2))
    half_difference = hypot(0.5_wp * (a(1,1) - a(2,2)), a(1,2))
    lambda_max = mean + half_difference
    lambda_min = (a(1,1) * a(2,2) - a(1,2)**2) / lambda_max    ! avoids cancellation when lambda_min << lambda_max
    if (lambda_max <= 0.0_wp) lambda_min = mean - half_difference
  end subroutine symmetric_eigenvalues

end module closest_points
