!> Hard-body collisions of two rigid spheroids (paper section 2.2.4 after Jain, Tschisgale &
!> Froehlich 2019; docs/physics.md section 6).
!> Detection (paper: a dynamic distance scaled by the approaching normal velocity): a collision
!> happens when the pair approaches (v_n > 0 at the closest points) and the surface gap is below
!>   d_detect = max(detection_floor, detection_factor * v_n * dt).
!> Impulse at x_c = (x1 + x2)/2 with normal n from 1 to 2, lever arms r_i = x_c - X_i, relative
!> contact velocity v = (U1 + w1 x r1) - (U2 + w2 x r2), v_n = v.n > 0 approaching, and
!>   K = (1/m1 + 1/m2) I - [r1]x i1^-1 [r1]x - [r2]x i2^-1 [r2]x   (Eq. 20 summed over both bodies)
!> so that an impulse J (on 2; -J on 1) changes v by -K J. The impulse is applied as
!> U1 -= J/m1, w1 -= i1^-1 (r1 x J), U2 += J/m2, w2 += i2^-1 (r2 x J): linear and angular momentum
!> are conserved exactly (both bodies receive it at the same point). With the bodies' added masses
!> (a fluid whose reaction is taken implicitly, module rigid_body), 1/m_i and i_i^-1 become
!> R_i (m_i + M_a,i)^-1 R_i^T and R_i (I_i + I_a,i)^-1 R_i^T in K and in the update; the energy is
!> then that of the bodies and their added masses. Models:
!>  - 'paper' (Eqs. 23-24): post-collision contact velocity -e v_n n, tangential slip removed:
!>    J = K^-1 (v + e v_n n). Its energy change is dE = -(v^T M v - e^2 v_n^2 n^T M n)/2 with M = K^-1,
!>    which can be positive when K couples normal and tangential directions strongly (an eccentric
!>    contact on an elongated body with large slip). Then e is lowered to the elastic limit
!>    e_max = sqrt(v^T M v / (v_n^2 n^T M n)) (dE = 0) and the result says so (restitution_used < e).
!>  - 'frictionless': J = j n, j = (1 + e) v_n / (n^T K n); dE = -j (1 - e) v_n / 2 <= 0.
!>  - 'coulomb': the sticking impulse of 'paper' if its tangential part is within the cone
!>    |J_t| <= mu_c J.n, else sliding: J = j (n + mu_c t), t = initial slip direction, with
!>    j = (1 + e) v_n / (n^T K (n + mu_c t)); if that would not dissipate energy (possible for
!>    strongly coupled K) the frictionless impulse is used and the result says so.
module collision
  use agglo_kinds, only: wp
  use vector_algebra, only: skew, cross
  use config_collision, only: collision_config_t
  use rigid_body, only: rigid_body_t, added_inertia_t, inverse_inertia_lab, inverse_mass_lab, point_velocity, &
                        set_angular_velocity_lab, angular_velocity_lab, kinetic_energy, rigid_body_kick
  use closest_points, only: closest_points_t
  use logger, only: log_line
  implicit none
  private
  public :: collision_model_t, collision_result_t, collision_setup, collision_log_settings, detection_distance, &
            collision_detected, approach_speed, collide, contact_matrix, contact_impulse, isotropic_inverse_mass, &
            normal_speed_at, normal_correction

  !> Both take either the closest-points result of the pair or its parts (gap, points, normal).
  interface collision_detected
    module procedure collision_detected_gap, collision_detected_contact
  end interface collision_detected
  interface collide
    module procedure collide_points, collide_contact
  end interface collide
  public :: collision_paper, collision_frictionless, collision_coulomb
  public :: regime_stick, regime_slide, regime_frictionless, regime_elastic_limit, regime_no_impulse

  integer, parameter :: collision_paper = 1, collision_frictionless = 2, collision_coulomb = 3
  !> How the impulse was closed (collision_result_t%regime).
  integer, parameter :: regime_no_impulse = 0, regime_stick = 1, regime_slide = 2, regime_frictionless = 3, &
                        regime_elastic_limit = 4

  type :: collision_model_t
    integer :: model = collision_paper
    real(wp) :: restitution = 0.4_wp
    real(wp) :: friction_coefficient = 0.0_wp
    real(wp) :: detection_floor = 1.0e-9_wp   !< m
    real(wp) :: detection_factor = 1.0_wp
    !> cap on the sequential-impulse sweeps over the contacts of one step (module particle_system)
    integer :: max_sweeps = 200
  end type collision_model_t

  !> What one collision did (for the events table).
  type :: collision_result_t
    real(wp) :: impulse(3) = 0.0_wp            !< N s, applied to body 2 (body 1 receives -impulse), lab
    real(wp) :: contact_point(3) = 0.0_wp      !< m, x_c = (x1 + x2)/2
    real(wp) :: normal(3) = 0.0_wp             !< unit normal from 1 to 2
    real(wp) :: normal_velocity_before = 0.0_wp  !< m/s, v.n at x_c, > 0 approaching
    real(wp) :: normal_velocity_after = 0.0_wp   !< m/s, same sign convention (< 0 separating)
    real(wp) :: restitution_used = 0.0_wp      !< e actually applied (< e only at the elastic limit)
    real(wp) :: energy_change = 0.0_wp         !< J, kinetic energy after - before (<= 0)
    integer :: regime = regime_no_impulse
  end type collision_result_t

contains

  subroutine collision_setup(model, cfg)
    type(collision_model_t), intent(out) :: model
    type(collision_config_t), intent(in) :: cfg
    select case (cfg%model)
    case ('frictionless'); model%model = collision_frictionless
    case ('coulomb'); model%model = collision_coulomb
    case default; model%model = collision_paper
    end select
    model%restitution = cfg%restitution
    model%friction_coefficient = cfg%friction_coefficient
    model%detection_floor = cfg%detection_floor
    model%detection_factor = cfg%detection_factor
    model%max_sweeps = cfg%max_impulse_sweeps
  end subroutine collision_setup

  subroutine collision_log_settings(model)
    type(collision_model_t), intent(in) :: model
    character(len=200) :: line
    character(len=16), parameter :: names(3) = [character(len=16) :: 'paper', 'frictionless', 'coulomb']
    write(line, '(a,a,a,f6.3,a,f6.3)') 'collision: model ''', trim(names(model%model)), ''', restitution e = ', &
        model%restitution, ', friction coefficient = ', model%friction_coefficient
    call log_line(trim(line))
    write(line, '(a,es11.4,a,f8.3,a)') 'collision: detection distance = max(', model%detection_floor, ' m, ', &
        model%detection_factor, ' v_n dt), only while approaching'
    call log_line(trim(line))
  end subroutine collision_log_settings

  !> d_detect = max(floor, factor * v_n * dt) for an approach speed v_n (> 0 approaching).
  pure real(wp) function detection_distance(model, normal_speed, dt)
    type(collision_model_t), intent(in) :: model
    real(wp), intent(in) :: normal_speed, dt
    detection_distance = max(model%detection_floor, model%detection_factor * max(normal_speed, 0.0_wp) * dt)
  end function detection_distance

  !> A collision: approaching and the gap (signed, < 0 overlap) below the detection distance.
  pure logical function collision_detected_gap(model, gap, normal_speed, dt)
    type(collision_model_t), intent(in) :: model
    real(wp), intent(in) :: gap, normal_speed, dt
    collision_detected_gap = normal_speed > 0.0_wp .and. gap < detection_distance(model, normal_speed, dt)
  end function collision_detected_gap

  !> The same test from the pair's closest points (module closest_points) and the bodies' velocities.
  pure logical function collision_detected_contact(model, body1, body2, contact, dt)
    type(collision_model_t), intent(in) :: model
    type(rigid_body_t), intent(in) :: body1, body2
    type(closest_points_t), intent(in) :: contact
    real(wp), intent(in) :: dt
    collision_detected_contact = collision_detected_gap(model, contact%gap, &
        approach_speed(body1, body2, contact%point1, contact%point2, contact%normal), dt)
  end function collision_detected_contact

  !> collide() from the pair's closest points.
  pure subroutine collide_contact(model, body1, body2, contact, result, added1, added2)
    type(collision_model_t), intent(in) :: model
    type(rigid_body_t), intent(inout) :: body1, body2
    type(closest_points_t), intent(in) :: contact
    type(collision_result_t), intent(out) :: result
    type(added_inertia_t), intent(in), optional :: added1, added2
    call collide_points(model, body1, body2, contact%point1, contact%point2, contact%normal, result, added1, added2)
  end subroutine collide_contact

  !> Normal approach speed of the closest points x1 (on body 1) and x2 (on body 2):
  !> (u(x1) - u(x2)).n, > 0 approaching (n from 1 to 2).
  pure real(wp) function approach_speed(body1, body2, point1, point2, normal)
    type(rigid_body_t), intent(in) :: body1, body2
    real(wp), intent(in) :: point1(3), point2(3), normal(3)
    approach_speed = dot_product(point_velocity(body1, point1) - point_velocity(body2, point2), normal)
  end function approach_speed

  !> K of the pair at lever arms r1, r2 (docs/physics.md section 6); inverse_mass: the sum of the
  !> two bodies' inverse mass tensors (isotropic_inverse_mass(1/m1 + 1/m2) for bodies alone).
  pure function contact_matrix(inverse_mass, inverse_inertia1, lever1, inverse_inertia2, lever2) result(k)
    real(wp), intent(in) :: inverse_mass(3, 3), inverse_inertia1(3, 3), lever1(3), inverse_inertia2(3, 3), lever2(3)
    real(wp) :: k(3, 3), s1(3, 3), s2(3, 3)
    s1 = skew(lever1)
    s2 = skew(lever2)
    k = -matmul(s1, matmul(inverse_inertia1, s1)) - matmul(s2, matmul(inverse_inertia2, s2)) + inverse_mass
    k = 0.5_wp * (k + transpose(k))   ! symmetric by construction; remove round-off asymmetry
  end function contact_matrix

  !> The inverse mass tensor s I of bodies without added mass (s = 1/m1 + 1/m2).
  pure function isotropic_inverse_mass(inverse_mass_sum) result(tensor)
    real(wp), intent(in) :: inverse_mass_sum
    real(wp) :: tensor(3, 3)
    integer :: i
    tensor = 0.0_wp
    do i = 1, 3
      tensor(i, i) = inverse_mass_sum
    end do
  end function isotropic_inverse_mass

  !> The impulse J (on body 2) for relative contact velocity v (1 minus 2), normal n (1 -> 2) and
  !> contact matrix K; requires v.n > 0. Pure algebra, no bodies (unit-testable with plain matrices).
  pure subroutine contact_impulse(model, k, relative_velocity, normal, impulse, regime, restitution_used)
    type(collision_model_t), intent(in) :: model
    real(wp), intent(in) :: k(3, 3), relative_velocity(3), normal(3)
    real(wp), intent(out) :: impulse(3), restitution_used
    integer, intent(out) :: regime
    real(wp) :: m(3, 3), v(3), n(3), vn, e, vmv, nmn, e_max, jn, jt(3), slip(3), t(3), denominator, j
    v = relative_velocity
    n = normal
    vn = dot_product(v, n)
    e = model%restitution
    impulse = 0.0_wp
    restitution_used = e
    regime = regime_no_impulse
    if (.not. (vn > 0.0_wp)) return
    if (model%model == collision_frictionless) then
      impulse = frictionless_impulse(k, n, vn, e)
      regime = regime_frictionless
      return
    end if
    ! Sticking impulse (paper, Eqs. 23-24): K J = v + e v_n n, limited to the elastic bound.
    m = inverse3(k)
    vmv = dot_product(v, matmul(m, v))
    nmn = vn**2 * dot_product(n, matmul(m, n))
    regime = regime_stick
    if (e**2 * nmn > vmv) then
      e_max = sqrt(max(vmv, 0.0_wp) / nmn)
      restitution_used = e_max
      regime = regime_elastic_limit
    end if
    impulse = matmul(m, v + restitution_used * vn * n)
    if (model%model /= collision_coulomb) return
    jn = dot_product(impulse, n)
    jt = impulse - jn * n
    if (norm2(jt) <= model%friction_coefficient * jn) return
    ! Sliding: friction on body 1 opposes its slip relative to body 2 (v_t), so J_t is along +t.
    slip = v - vn * n
    if (norm2(slip) > 1.0e-12_wp * abs(vn)) then
      t = slip / norm2(slip)
    else
      t = jt / norm2(jt)
    end if
    restitution_used = e
    denominator = dot_product(n, matmul(k, n + model%friction_coefficient * t))
    if (denominator > 0.0_wp) then
      j = (1.0_wp + e) * vn / denominator
      impulse = j * (n + model%friction_coefficient * t)
      regime = regime_slide
      ! Kinetic energy change -J.(v + v')/2 with v' = v - K J must not be positive.
      if (-dot_product(impulse, 2.0_wp * v - matmul(k, impulse)) <= 0.0_wp) return
    end if
    impulse = frictionless_impulse(k, n, vn, e)
    regime = regime_frictionless
  end subroutine contact_impulse

  !> J = j n with n.(v - K J) = -e v_n: j = (1 + e) v_n / (n^T K n).
  pure function frictionless_impulse(k, normal, normal_speed, restitution) result(impulse)
    real(wp), intent(in) :: k(3, 3), normal(3), normal_speed, restitution
    real(wp) :: impulse(3)
    impulse = (1.0_wp + restitution) * normal_speed / dot_product(normal, matmul(k, normal)) * normal
  end function frictionless_impulse

  !> Resolve a collision between body1 and body2 with closest points x1, x2 and normal n (1 -> 2):
  !> impulse at x_c = (x1 + x2)/2, both bodies updated in place. Nothing happens if the contact
  !> point is not approaching (result%regime = regime_no_impulse).
  !> added1, added2 (both or neither): the bodies' added masses, carried through the impulse.
  pure subroutine collide_points(model, body1, body2, point1, point2, normal, result, added1, added2)
    type(collision_model_t), intent(in) :: model
    type(rigid_body_t), intent(inout) :: body1, body2
    real(wp), intent(in) :: point1(3), point2(3), normal(3)
    type(collision_result_t), intent(out) :: result
    type(added_inertia_t), intent(in), optional :: added1, added2
    real(wp) :: xc(3), r1(3), r2(3), v(3), k(3, 3), inv1(3, 3), inv2(3, 3), n(3), energy_before
    logical :: in_fluid
    in_fluid = present(added1) .and. present(added2)
    n = normal / norm2(normal)
    xc = 0.5_wp * (point1 + point2)
    r1 = xc - body1%position
    r2 = xc - body2%position
    v = point_velocity(body1, xc) - point_velocity(body2, xc)
    ! An absent added1, added2 passes on as absent: the bodies alone.
    inv1 = inverse_inertia_lab(body1, added1)
    inv2 = inverse_inertia_lab(body2, added2)
    if (in_fluid) then
      k = contact_matrix(inverse_mass_lab(body1, added1) + inverse_mass_lab(body2, added2), inv1, r1, inv2, r2)
    else
      k = contact_matrix(isotropic_inverse_mass(1.0_wp / body1%mass + 1.0_wp / body2%mass), inv1, r1, inv2, r2)
    end if
    energy_before = kinetic_energy(body1, added1) + kinetic_energy(body2, added2)
    result%contact_point = xc
    result%normal = n
    result%normal_velocity_before = dot_product(v, n)
    call contact_impulse(model, k, v, n, result%impulse, result%regime, result%restitution_used)
    if (result%regime /= regime_no_impulse) then
      if (in_fluid) then
        call rigid_body_kick(body1, -result%impulse, cross(r1, -result%impulse), 1.0_wp, added1)
        call rigid_body_kick(body2, result%impulse, cross(r2, result%impulse), 1.0_wp, added2)
      else
        body1%velocity = body1%velocity - result%impulse / body1%mass
        body2%velocity = body2%velocity + result%impulse / body2%mass
        call set_angular_velocity_lab(body1, angular_velocity_lab(body1) - matmul(inv1, cross(r1, result%impulse)))
        call set_angular_velocity_lab(body2, angular_velocity_lab(body2) + matmul(inv2, cross(r2, result%impulse)))
      end if
    end if
    result%normal_velocity_after = dot_product(point_velocity(body1, xc) - point_velocity(body2, xc), n)
    result%energy_change = kinetic_energy(body1, added1) + kinetic_energy(body2, added2) - energy_before
  end subroutine collide_points

  !> Normal approach speed (m/s, > 0 approaching) of the material points of both bodies at the
  !> contact point x_c = (x1 + x2)/2, normal n from 1 to 2 (the v_n of collide()).
  pure real(wp) function normal_speed_at(body1, body2, point1, point2, normal)
    type(rigid_body_t), intent(in) :: body1, body2
    real(wp), intent(in) :: point1(3), point2(3), normal(3)
    real(wp) :: xc(3)
    xc = 0.5_wp * (point1 + point2)
    normal_speed_at = dot_product(point_velocity(body1, xc) - point_velocity(body2, xc), normal / norm2(normal))
  end function normal_speed_at

  !> A normal impulse dj n at x_c = (x1 + x2)/2 (on body 2; -dj n on body 1) that sets the normal
  !> speed at x_c to -separation_speed (one projected Gauss-Seidel update of a contact: docs/theory.md,
  !> "Particle system"): dj = (v_n + s) / (n^T K n), limited to dj >= -accumulated so that the
  !> contact's total normal impulse stays >= 0 (a contact pushes, never pulls). accumulated is
  !> updated; impulse: the impulse applied to body 2 (N s, lab). Momentum is conserved exactly as in
  !> collide(); added1, added2 (both or neither) as there.
  pure subroutine normal_correction(body1, body2, point1, point2, normal, separation_speed, accumulated, impulse, &
                                    added1, added2)
    type(rigid_body_t), intent(inout) :: body1, body2
    real(wp), intent(in) :: point1(3), point2(3), normal(3), separation_speed
    real(wp), intent(inout) :: accumulated
    real(wp), intent(out) :: impulse(3)
    type(added_inertia_t), intent(in), optional :: added1, added2
    real(wp) :: xc(3), r1(3), r2(3), n(3), k(3, 3), inv1(3, 3), inv2(3, 3), vn, dj
    logical :: in_fluid
    in_fluid = present(added1) .and. present(added2)
    n = normal / norm2(normal)
    xc = 0.5_wp * (point1 + point2)
    r1 = xc - body1%position
    r2 = xc - body2%position
    vn = dot_product(point_velocity(body1, xc) - point_velocity(body2, xc), n)
    inv1 = inverse_inertia_lab(body1, added1)
    inv2 = inverse_inertia_lab(body2, added2)
    if (in_fluid) then
      k = contact_matrix(inverse_mass_lab(body1, added1) + inverse_mass_lab(body2, added2), inv1, r1, inv2, r2)
    else
      k = contact_matrix(isotropic_inverse_mass(1.0_wp / body1%mass + 1.0_wp / body2%mass), inv1, r1, inv2, r2)
    end if
    dj = max((vn + separation_speed) / dot_product(n, matmul(k, n)), -accumulated)
    accumulated = accumulated + dj
    impulse = dj * n
    if (in_fluid) then
      call rigid_body_kick(body1, -impulse, cross(r1, -impulse), 1.0_wp, added1)
      call rigid_body_kick(body2, impulse, cross(r2, impulse), 1.0_wp, added2)
    else
      body1%velocity = body1%velocity - impulse / body1%mass
      body2%velocity = body2%velocity + impulse / body2%mass
      call set_angular_velocity_lab(body1, angular_velocity_lab(body1) - matmul(inv1, cross(r1, impulse)))
      call set_angular_velocity_lab(body2, angular_velocity_lab(body2) + matmul(inv2, cross(r2, impulse)))
    end if
  end subroutine normal_correction

  !> Inverse of a 3x3 matrix by cofactors (K is symmetric positive definite: m > 0, I > 0).
  pure function inverse3(a) result(b)
    real(wp), intent(in) :: a(3, 3)
    real(wp) :: b(3, 3), det
    b(1, 1) = a(2, 2) * a(3, 3) - a(2, 3) * a(3, 2)
    b(1, 2) = a(1, 3) * a(3, 2) - a(1, 2) * a(3, 3)
    b(1, 3) = a(1, 2) * a(2, 3) - a(1, 3) * a(2, 2)
    b(2, 1) = a(2, 3) * a(3, 1) - a(2, 1) * a(3, 3)
    b(2, 2) = a(1, 1) * a(3, 3) - a(1, 3) * a(3, 1)
    b(2, 3) = a(1, 3) * a(2, 1) - a(1, 1) * a(2, 3)
    b(3, 1) = a(2, 1) * a(3, 2) - a(2, 2) * a(3, 1)
    b(3, 2) = a(1, 2) * a(3, 1) - a(1, 1) * a(3, 2)
    b(3, 3) = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1)
    det = a(1, 1) * b(1, 1) + a(1, 2) * b(2, 1) + a(1, 3) * b(3, 1)
    b = b / det
  end function inverse3
end module collision
