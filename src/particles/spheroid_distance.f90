!> Closest surface point, outward unit normal and signed distance from an arbitrary point (inside or
!> outside) to a spheroid (semi-axis a along body x, b = c), for the immersed boundary's ghost nodes.
!>
!> By the rotational symmetry about body x, the closest point lies in the meridian plane through the
!> point, so the 3-D problem reduces to the distance from (|x|, sqrt(y^2 + z^2)) to the ellipse
!> u^2/a^2 + w^2/b^2 = 1 in the first quadrant. That is solved by Eberly's robust method (D. Eberly,
!> "Distance from a point to an ellipse, an ellipsoid, or a hyperellipsoid", Geometric Tools, 2013):
!> with semi-axes e0 >= e1 and the point (y0, y1), y0, y1 > 0, the closest point is
!> x0 = e0^2 y0/(t + e0^2), x1 = e1^2 y1/(t + e1^2), where t is the unique root in t > -e1^2 of
!> F(t) = (e0 y0/(t + e0^2))^2 + (e1 y1/(t + e1^2))^2 - 1, a strictly decreasing function there (for
!> points inside, t < 0; outside, t > 0), found by bisection to the last bit. The root is sought here
!> in the shifted variable sigma = t/e1^2 + 1 > 0 (Eberly bisects s = t/e1^2), so that near the
!> major axis inside the body, where s -> -1, the small quantity s + 1 keeps its relative precision.
!> The points on an axis (y0 = 0 or y1 = 0, the centre included) are Eberly's closed-form cases.
!> docs/theory.md, "Immersed boundary geometry".
module spheroid_distance
  use agglo_kinds, only: wp
  use spheroid, only: spheroid_t, normal_at_point
  use quaternion, only: rotate_to_body, rotate_to_lab
  implicit none
  private
  public :: surface_projection_t, ellipse_closest_point, body_closest_point, lab_closest_point

  !> The projection of a point onto a spheroid's surface.
  type :: surface_projection_t
    real(wp) :: point(3) = 0.0_wp           !< m, the closest surface point
    real(wp) :: normal(3) = 0.0_wp          !< outward unit normal there
    real(wp) :: signed_distance = 0.0_wp    !< m, |x - point|, negative for a point inside
  end type surface_projection_t

  !> Iterations at most: enough for the bisection alone to reach the last bit of any double-precision
  !> root (the interval halves each step; 53 bits of mantissa plus the 1074 binary orders down to the
  !> smallest subnormal), as Eberly's bound; the safeguarded Newton iteration takes far fewer.
  integer, parameter :: max_bisections = 1130

contains

  !> Closest point (x0, x1) of the ellipse x0^2/e0^2 + x1^2/e1^2 = 1 (e0 >= e1 > 0) to the point
  !> (y0, y1) with y0, y1 >= 0 (Eberly 2013, section 2.9's robust algorithm), and the distance.
  !> When the closest point is not unique (a point on the major axis inside the evolute, or the
  !> centre) the one with x1 >= 0 is returned.
  pure subroutine ellipse_closest_point(e0, e1, y0, y1, x0, x1, distance)
    real(wp), intent(in) :: e0, e1, y0, y1
    real(wp), intent(out) :: x0, x1, distance
    real(wp) :: z0, z1, g, r0, sigma, numerator, denominator, ratio
    if (y1 > 0.0_wp) then
      if (y0 > 0.0_wp) then
        z0 = y0 / e0
        z1 = y1 / e1
        g = z0**2 + z1**2 - 1.0_wp
        if (g /= 0.0_wp) then
          r0 = (e0 / e1)**2
          sigma = shifted_root(r0 - 1.0_wp, r0 * z0, z1, g)
          x0 = r0 * y0 / (sigma + (r0 - 1.0_wp))
          x1 = y1 / sigma
        else
          x0 = y0
          x1 = y1
        end if
      else
        ! On the minor axis: the co-vertex (the distance decreases monotonically towards it).
        x0 = 0.0_wp
        x1 = e1
      end if
    else
      ! On the major axis: off-axis closest point inside the evolute, y0 < (e0^2 - e1^2)/e0.
      numerator = e0 * y0
      denominator = e0**2 - e1**2
      if (numerator < denominator) then
        ratio = numerator / denominator
        x0 = e0 * ratio
        x1 = e1 * sqrt(1.0_wp - ratio**2)
      else
        x0 = e0
        x1 = 0.0_wp
      end if
    end if
    distance = hypot(x0 - y0, x1 - y1)
  end subroutine ellipse_closest_point

  !> Root sigma > 0 of G(sigma) = (n0/(sigma + r0m1))^2 + (z1/sigma)^2 - 1, with n0 = r0 z0,
  !> r0m1 = r0 - 1 >= 0, z1 > 0; G decreases strictly and is convex on sigma > 0. Bracket: G(z1) >= 0,
  !> and G <= 0 at sigma = 1 for a point inside (g < 0) or at sigma = |(n0, z1)| outside (g > 0).
  !> Safeguarded Newton iteration: G(1) = g, so sigma = 1 is the root for a point on the surface and
  !> the start for every point (clamped into the bracket); each evaluation narrows the bracket by the
  !> sign of G, and a Newton iterate outside the bracket is replaced by its midpoint (the bisection of
  !> Eberly 2013). By the convexity, after at most one step from the right the iterates rise
  !> monotonically to the root; the iteration stops when a step no longer changes sigma or the
  !> bracket has no interior float, i.e. at the root to the last bits, as the bisection alone (about
  !> 5 evaluations near the surface, where the ghost nodes are, against 50-70 bisection steps). For a
  !> circle (r0 = 1: a sphere) the root is closed-form, sigma = |(n0, z1)|.
  pure function shifted_root(r0m1, n0, z1, g) result(sigma)
    real(wp), intent(in) :: r0m1, n0, z1, g
    real(wp) :: sigma, lo, hi, value, slope, next
    integer :: iteration
    if (r0m1 == 0.0_wp) then   ! a circle (a sphere's meridian): G = |(n0, z1)|^2/sigma^2 - 1
      sigma = hypot(n0, z1)
      return
    end if
    lo = z1
    if (g < 0.0_wp) then
      hi = 1.0_wp
    else
      hi = hypot(n0, z1)
    end if
    sigma = min(max(1.0_wp, lo), hi)
    do iteration = 1, max_bisections
      value = (n0 / (sigma + r0m1))**2 + (z1 / sigma)**2 - 1.0_wp
      if (value > 0.0_wp) then
        lo = sigma
      else if (value < 0.0_wp) then
        hi = sigma
      else
        exit
      end if
      slope = -2.0_wp * (n0**2 / (sigma + r0m1)**3 + z1**2 / sigma**3)
      next = sigma - value / slope
      if (next == sigma) exit                                           ! the step is below the last bit
      if (.not. (next > lo .and. next < hi)) next = 0.5_wp * (lo + hi)
      if (.not. (next > lo .and. next < hi)) exit                       ! no float left between lo and hi
      sigma = next
    end do
  end function shifted_root

  !> Projection of the body-frame point p onto the spheroid s (body frame). On the symmetry axis of
  !> a prolate body inside its evolute, and at the centre of a sphere or a prolate body, the
  !> closest point is a circle (or the whole sphere): the one in the body x-y plane with y >= 0
  !> (and x >= 0) is returned.
  pure function body_closest_point(s, p) result(projection)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: p(3)
    type(surface_projection_t) :: projection
    real(wp) :: axial, radial, axial_closest, radial_closest, distance, radial_direction(2)
    logical :: inside
    axial = abs(p(1))
    radial = hypot(p(2), p(3))
    if (s%a >= s%b) then
      call ellipse_closest_point(s%a, s%b, axial, radial, axial_closest, radial_closest, distance)
    else
      call ellipse_closest_point(s%b, s%a, radial, axial, radial_closest, axial_closest, distance)
    end if
    if (radial > 0.0_wp) then
      radial_direction = p(2:3) / radial
    else
      radial_direction = [1.0_wp, 0.0_wp]
    end if
    projection%point = [merge(-axial_closest, axial_closest, p(1) < 0.0_wp), radial_closest * radial_direction]
    projection%normal = normal_at_point(s, projection%point)
    inside = (axial / s%a)**2 + (radial / s%b)**2 < 1.0_wp
    projection%signed_distance = merge(-distance, distance, inside)
  end function body_closest_point

  !> Projection of the lab point x onto the body with centre `centre` and orientation q (body ->
  !> lab, quaternion.f90). Point and normal in the lab frame. Periodic images are the caller's:
  !> x - centre is used as given.
  pure function lab_closest_point(s, centre, q, x) result(projection)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: centre(3), q(4), x(3)
    type(surface_projection_t) :: projection
    projection = body_closest_point(s, rotate_to_body(q, x - centre))
    projection%point = centre + rotate_to_lab(q, projection%point)
    projection%normal = rotate_to_lab(q, projection%normal)
  end function lab_closest_point

end module spheroid_distance
