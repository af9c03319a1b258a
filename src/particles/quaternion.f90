!> Unit quaternions, scalar first: q = (w, x, y, z) = (cos(angle/2), sin(angle/2) axis).
!> Convention (docs/physics.md section 0): q rotates body -> lab, v_lab = R(q) v_body = q (x) (0, v) (x) q*,
!> and the kinematics are dq/dt = 1/2 q (x) (0, omega_body) with omega_body the angular velocity
!> in body axes. Quaternions are plain real(wp) arrays of size 4 so that they can be stored,
!> written and communicated without a derived type.
module quaternion
  use agglo_kinds, only: wp
  use physical_constants, only: two_pi
  use random_stream, only: random_stream_t, stream_uniform
  implicit none
  private
  public :: quaternion_identity, quaternion_product, quaternion_conjugate, quaternion_normalise, &
            quaternion_norm, rotation_matrix, rotate_to_lab, rotate_to_body, &
            quaternion_from_axis_angle, quaternion_to_axis_angle, quaternion_from_matrix, &
            random_orientation, quaternion_rate, quaternion_advance, symmetry_axis

  real(wp), parameter :: quaternion_identity(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]

contains

  !> Hamilton product p (x) q.
  pure function quaternion_product(p, q) result(r)
    real(wp), intent(in) :: p(4), q(4)
    real(wp) :: r(4)
    r(1) = p(1)*q(1) - p(2)*q(2) - p(3)*q(3) - p(4)*q(4)
    r(2) = p(1)*q(2) + p(2)*q(1) + p(3)*q(4) - p(4)*q(3)
    r(3) = p(1)*q(3) - p(2)*q(4) + p(3)*q(1) + p(4)*q(2)
    r(4) = p(1)*q(4) + p(2)*q(3) - p(3)*q(2) + p(4)*q(1)
  end function quaternion_product

  pure function quaternion_conjugate(q) result(r)
    real(wp), intent(in) :: q(4)
    real(wp) :: r(4)
    r = [q(1), -q(2), -q(3), -q(4)]
  end function quaternion_conjugate

  pure function quaternion_norm(q) result(n)
    real(wp), intent(in) :: q(4)
    real(wp) :: n
    n = norm2(q)
  end function quaternion_norm

  !> q / |q|. A zero quaternion has no orientation: it is returned unchanged (the caller checks
  !> inputs from decks with quaternion_norm before normalising).
  pure function quaternion_normalise(q) result(r)
    real(wp), intent(in) :: q(4)
    real(wp) :: r(4), n
    n = norm2(q)
    if (n > 0.0_wp) then
      r = q / n
    else
      r = q
    end if
  end function quaternion_normalise

  !> Rotation matrix R(q), body -> lab (v_lab = matmul(R, v_body)); its columns are the body axes
  !> in the lab frame. q must be a unit quaternion.
  pure function rotation_matrix(q) result(r)
    real(wp), intent(in) :: q(4)
    real(wp) :: r(3,3)
    real(wp) :: w, x, y, z
    w = q(1); x = q(2); y = q(3); z = q(4)
    r(1,1) = 1.0_wp - 2.0_wp*(y*y + z*z)
    r(1,2) = 2.0_wp*(x*y - w*z)
    r(1,3) = 2.0_wp*(x*z + w*y)
    r(2,1) = 2.0_wp*(x*y + w*z)
    r(2,2) = 1.0_wp - 2.0_wp*(x*x + z*z)
    r(2,3) = 2.0_wp*(y*z - w*x)
    r(3,1) = 2.0_wp*(x*z - w*y)
    r(3,2) = 2.0_wp*(y*z + w*x)
    r(3,3) = 1.0_wp - 2.0_wp*(x*x + y*y)
  end function rotation_matrix

  !> Symmetry axis (body x) in the lab frame: the first column of R(q).
  pure function symmetry_axis(q) result(e)
    real(wp), intent(in) :: q(4)
    real(wp) :: e(3)
    e = [1.0_wp - 2.0_wp*(q(3)**2 + q(4)**2), 2.0_wp*(q(2)*q(3) + q(1)*q(4)), 2.0_wp*(q(2)*q(4) - q(1)*q(3))]
  end function symmetry_axis

  !> v_lab = R(q) v_body.
  pure function rotate_to_lab(q, v_body) result(v_lab)
    real(wp), intent(in) :: q(4), v_body(3)
    real(wp) :: v_lab(3)
    v_lab = matmul(rotation_matrix(q), v_body)
  end function rotate_to_lab

  !> v_body = R(q)^T v_lab.
  pure function rotate_to_body(q, v_lab) result(v_body)
    real(wp), intent(in) :: q(4), v_lab(3)
    real(wp) :: v_body(3)
    v_body = matmul(v_lab, rotation_matrix(q))
  end function rotate_to_body

  !> Rotation by angle (rad, right-handed) about axis (any non-zero length; normalised here).
  !> A zero axis gives the identity with any angle only if angle = 0; otherwise the caller must
  !> reject it (decks: the pair group checks the axis length before calling).
  pure function quaternion_from_axis_angle(axis, angle) result(q)
    real(wp), intent(in) :: axis(3), angle
    real(wp) :: q(4), length
    length = norm2(axis)
    if (length > 0.0_wp) then
      q = [cos(0.5_wp*angle), sin(0.5_wp*angle) * axis / length]
    else
      q = quaternion_identity
    end if
  end function quaternion_from_axis_angle

  !> Axis (unit) and angle in [0, pi] of a unit quaternion (q and -q are the same rotation; the
  !> representative with w >= 0 is used). The identity returns axis (1, 0, 0) and angle 0.
  pure subroutine quaternion_to_axis_angle(q, axis, angle)
    real(wp), intent(in) :: q(4)
    real(wp), intent(out) :: axis(3), angle
    real(wp) :: p(4), sine_half
    p = q
    if (p(1) < 0.0_wp) p = -p
    sine_half = norm2(p(2:4))
    ! atan2 keeps full accuracy for small and for near-pi angles (acos(w) would not).
    angle = 2.0_wp * atan2(sine_half, p(1))
    if (sine_half > 0.0_wp) then
      axis = p(2:4) / sine_half
    else
      axis = [1.0_wp, 0.0_wp, 0.0_wp]
    end if
  end subroutine quaternion_to_axis_angle

  !> Unit quaternion (w >= 0) of a proper rotation matrix, by Shepperd's method (J. Guidance
  !> Control 1, 223, 1978): the largest of the four squared components is taken from the trace
  !> so that no division by a small number occurs.
  pure function quaternion_from_matrix(r) result(q)
    real(wp), intent(in) :: r(3,3)
    real(wp) :: q(4), trace, s
    trace = r(1,1) + r(2,2) + r(3,3)
    if (trace >= max(r(1,1), r(2,2), r(3,3))) then
      s = 2.0_wp * sqrt(1.0_wp + trace)
      q = [0.25_wp*s, (r(3,2) - r(2,3))/s, (r(1,3) - r(3,1))/s, (r(2,1) - r(1,2))/s]
    else if (r(1,1) >= r(2,2) .and. r(1,1) >= r(3,3)) then
      s = 2.0_wp * sqrt(1.0_wp + r(1,1) - r(2,2) - r(3,3))
      q = [(r(3,2) - r(2,3))/s, 0.25_wp*s, (r(1,2) + r(2,1))/s, (r(1,3) + r(3,1))/s]
    else if (r(2,2) >= r(3,3)) then
      s = 2.0_wp * sqrt(1.0_wp + r(2,2) - r(1,1) - r(3,3))
      q = [(r(1,3) - r(3,1))/s, (r(1,2) + r(2,1))/s, 0.25_wp*s, (r(2,3) + r(3,2))/s]
    else
      s = 2.0_wp * sqrt(1.0_wp + r(3,3) - r(1,1) - r(2,2))
      q = [(r(2,1) - r(1,2))/s, (r(1,3) + r(3,1))/s, (r(2,3) + r(3,2))/s, 0.25_wp*s]
    end if
    if (q(1) < 0.0_wp) q = -q
    q = quaternion_normalise(q)
  end function quaternion_from_matrix

  !> Uniformly distributed rotation (Haar measure) by Shoemake's method (Graphics Gems III, 1992),
  !> docs/physics.md section 1. Uniform Euler angles would be biased.
  function random_orientation(stream) result(q)
    type(random_stream_t), intent(inout) :: stream
    real(wp) :: q(4), u1, u2, u3
    u1 = stream_uniform(stream)
    u2 = stream_uniform(stream)
    u3 = stream_uniform(stream)
    q = [sqrt(1.0_wp - u1) * sin(two_pi*u2), sqrt(1.0_wp - u1) * cos(two_pi*u2), &
         sqrt(u1) * sin(two_pi*u3), sqrt(u1) * cos(two_pi*u3)]
    q = quaternion_normalise(q)
  end function random_orientation

  !> dq/dt = 1/2 q (x) (0, omega_body) (docs/physics.md section 0), for integrators that need the rate.
  pure function quaternion_rate(q, omega_body) result(dq)
    real(wp), intent(in) :: q(4), omega_body(3)
    real(wp) :: dq(4)
    dq = 0.5_wp * quaternion_product(q, [0.0_wp, omega_body])
  end function quaternion_rate

  !> Exact solution of dq/dt = 1/2 q (x) (0, omega_body) over dt for omega_body constant in the body
  !> frame: q(t+dt) = q(t) (x) exp(1/2 (0, omega_body) dt), with exp((0, v)) = (cos|v|, sin|v| v/|v|).
  !> The increment is a unit quaternion, so |q| is kept to round-off; the result is renormalised so
  !> round-off cannot accumulate over millions of steps.
  pure function quaternion_advance(q, omega_body, dt) result(q_new)
    real(wp), intent(in) :: q(4), omega_body(3), dt
    real(wp) :: q_new(4), half_angle, sine_ratio, increment(4)
    half_angle = 0.5_wp * norm2(omega_body) * dt
    ! sin(x)/x, by its Taylor series where the quotient loses accuracy.
    if (half_angle < 1.0e-4_wp) then
      sine_ratio = 1.0_wp - half_angle**2 / 6.0_wp
    else
      sine_ratio = sin(half_angle) / half_angle
    end if
    increment = [cos(half_angle), 0.5_wp * dt * sine_ratio * omega_body]
    q_new = quaternion_normalise(quaternion_product(q, increment))
  end function quaternion_advance

end module quaternion
