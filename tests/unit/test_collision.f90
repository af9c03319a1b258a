! checks: 123
!> Unit tests of collision: restitution of head-on spheres, conservation laws and energy in random
!> oblique spheroid collisions (all three models), the same with random added masses and inertias
!> carried through the impulse (the momentum and energy of bodies and added masses, module
!> rigid_body "Impulses in a fluid"), the dynamic detection distance, and a sphere pair with DLVO +
!> collisions run at time steps from 1e-9 to 1e-5 s (no NaN, no overlap left).
program test_collision
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use config_collision, only: collision_config_t
  use config_dlvo, only: dlvo_config_t
  use collision, only: collision_model_t, collision_result_t, collision_setup, collide, detection_distance, &
                       collision_detected, approach_speed, contact_impulse, regime_stick, regime_slide, &
                       regime_elastic_limit
  use dlvo, only: dlvo_model_t, dlvo_setup, dlvo_pair_forces
  use rigid_body, only: rigid_body_t, rigid_body_init, rigid_body_step, kinetic_energy, linear_momentum, &
                        angular_momentum, integrator_euler, integrator_verlet, added_inertia_t
  use quaternion, only: rotate_to_lab, rotate_to_body, quaternion_normalise
  use vector_algebra, only: cross
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use test_framework, only: test_start, test_finish, check, check_close, check_below, check_equal
  implicit none
  real(wp), parameter :: r = 50.0e-6_wp, density = 2710.0_wp, restitutions(3) = [0.0_wp, 0.4_wp, 1.0_wp]
  type(collision_config_t) :: cfg
  type(collision_model_t) :: model
  real(wp) :: e, v(3), n(3), k(3, 3), impulse(3), used
  integer :: i, regime

  call test_start('collision')

  ! Head-on spheres (unequal masses): the normal relative velocity after is exactly -e times before
  ! (definition of e, docs/physics.md sec. 6), for every model and e in {0, 0.4, 1}.
  do i = 1, 3
    e = restitutions(i)
    cfg = collision_config_t(restitution=e)
    call head_on(cfg, 'paper')
    cfg%model = 'frictionless'
    call head_on(cfg, 'frictionless')
    cfg%model = 'coulomb'
    cfg%friction_coefficient = 0.3_wp
    call head_on(cfg, 'coulomb')
  end do

  ! Detection distance (paper: scales with the approach speed): floor, factor * v_n * dt, approach only.
  cfg = collision_config_t()
  call collision_setup(model, cfg)
  call check_close(detection_distance(model, 1.0e-3_wp, 2.0e-7_wp), 1.0e-9_wp, 1.0e-15_wp, 'detection_floor_at_slow_approach')
  call check_close(detection_distance(model, 1.0e-1_wp, 2.0e-7_wp), 2.0e-8_wp, 1.0e-15_wp, 'detection_scales_with_speed')
  call check(collision_detected(model, 0.5e-9_wp, 1.0e-3_wp, 2.0e-7_wp), 'detected_below_floor_approaching')
  call check(.not. collision_detected(model, 0.5e-9_wp, -1.0e-3_wp, 2.0e-7_wp), 'not_detected_when_separating')
  call check(.not. collision_detected(model, -1.0e-9_wp, 0.0_wp, 2.0e-7_wp), 'not_detected_at_rest_overlap')
  call check(.not. collision_detected(model, 2.0e-9_wp, 1.0e-3_wp, 2.0e-7_wp), 'not_detected_above_distance')

  ! The paper's closure on a plain 3x3 K with strong normal-tangential coupling: the restitution
  ! is lowered to the elastic limit (dE = 0), and a decoupled K gives exactly -e v_n n.
  cfg = collision_config_t(restitution=1.0_wp)
  call collision_setup(model, cfg)
  k = reshape([1.0_wp, 0.9_wp, 0.0_wp, 0.9_wp, 1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 1.0_wp], [3, 3])
  ! M = K^-1 = [[1, -0.9], [-0.9, 1]] / 0.19: v^T M v = 0.2/0.19 < e^2 v_n^2 n^T M n = 1/0.19 for v = (1, 1, 0).
  n = [1.0_wp, 0.0_wp, 0.0_wp]
  v = [1.0_wp, 1.0_wp, 0.0_wp]
  call contact_impulse(model, k, v, n, impulse, regime, used)
  call check_equal(regime, regime_elastic_limit, 'strong_coupling_elastic_limit')
  call check_below(abs(dot_product(impulse, 2.0_wp * v - matmul(k, impulse))), 1.0e-14_wp, 'elastic_limit_energy_zero')
  cfg%restitution = 0.4_wp
  call collision_setup(model, cfg)
  k = reshape([2.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 3.0_wp, 0.0_wp, 0.0_wp, 0.0_wp, 3.0_wp], [3, 3])
  call contact_impulse(model, k, v, n, impulse, regime, used)
  call check_below(norm2((v - matmul(k, impulse)) - (-0.4_wp * n)), 1.0e-15_wp, 'paper_post_velocity_minus_e_vn_n')
  call check_equal(regime, regime_stick, 'decoupled_k_is_stick')

  ! Random oblique collisions of needles, disks and mixed pairs.
  call random_collisions('paper', 0.4_wp)
  call random_collisions('paper', 1.0_wp)
  call random_collisions('frictionless', 0.4_wp)
  call random_collisions('frictionless', 1.0_wp)
  call random_collisions('coulomb', 0.4_wp)
  call random_collisions('paper', 0.4_wp, in_fluid=.true.)
  call random_collisions('coulomb', 0.4_wp, in_fluid=.true.)

  ! Sphere pair with DLVO and collisions at dt = 1e-9 ... 1e-5 s.
  call sphere_pair_time_steps()

  call test_finish()

contains

  subroutine head_on(config, label)
    type(collision_config_t), intent(in) :: config
    character(len=*), intent(in) :: label
    type(collision_model_t) :: m
    type(rigid_body_t) :: s1, s2
    type(collision_result_t) :: res
    real(wp) :: m1, m2, i1, i2, normal(3), p_before(3)
    character(len=8) :: tag
    call collision_setup(m, config)
    m1 = density * 4.0_wp / 3.0_wp * pi * r**3
    m2 = 3.0_wp * m1
    i1 = 0.4_wp * m1 * r**2
    i2 = 0.4_wp * m2 * r**2 * 3.0_wp**(2.0_wp / 3.0_wp)
    normal = [1.0_wp, 2.0_wp, 2.0_wp] / 3.0_wp
    call rigid_body_init(s1, m1, [i1, i1, i1], [0.0_wp, 0.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], &
                         velocity=0.7e-3_wp * normal)
    call rigid_body_init(s2, m2, [i2, i2, i2], 2.1_wp * r * normal, [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], &
                         velocity=-0.2e-3_wp * normal)
    p_before = linear_momentum(s1) + linear_momentum(s2)
    call collide(m, s1, s2, r * normal, 1.1_wp * r * normal, normal, res)
    write(tag, '(f3.1)') config%restitution
    call check_close(res%normal_velocity_after, -config%restitution * res%normal_velocity_before, 1.0e-14_wp, &
                     'head_on_restitution_'//label//'_e'//trim(tag), abs_tol=1.0e-14_wp * res%normal_velocity_before)
    call check_close(res%normal_velocity_before, 0.9e-3_wp, 1.0e-14_wp, 'head_on_approach_speed_'//label//'_e'//trim(tag))
    call check_below(norm2(linear_momentum(s1) + linear_momentum(s2) - p_before), 1.0e-13_wp * norm2(p_before), &
                     'head_on_momentum_'//label//'_e'//trim(tag))
  end subroutine head_on

  !> Two spheroids (aspect ratios from {5, 1/5, 20, 1/20, 1.0001}) in random orientations touching at
  !> exact common-normal points (a random surface point of body 1; body 2 placed so that its point
  !> with normal -n coincides, 1 nm further along n), with random velocities whose contact point
  !> approaches. Momentum about the origin before/after and energy after <= before.
  !> in_fluid: each body also carries random added masses and inertias (0 to 3 times its own, per
  !> axis); momentum and energy are then those of the bodies with their added masses.
  subroutine random_collisions(model_name, restitution, in_fluid)
    character(len=*), intent(in) :: model_name
    real(wp), intent(in) :: restitution
    logical, intent(in), optional :: in_fluid
    type(added_inertia_t) :: added1, added2
    logical :: fluid
    type(collision_config_t) :: config
    type(collision_model_t) :: m
    type(rigid_body_t) :: s1, s2
    type(collision_result_t) :: res
    type(random_stream_t) :: stream
    real(wp), parameter :: ratios(5) = [5.0_wp, 0.2_wp, 20.0_wp, 0.05_wp, 1.0001_wp]
    real(wp) :: axes1(2), axes2(2), q1(4), q2(4), x1(3), x2(3), normal(3), y(3), mb(3)
    real(wp) :: p0(3), l0(3), e0, scale_p, scale_l, worst_p, worst_l, worst_e, worst_e_elastic, worst_post
    real(wp) :: theta, phi, u1(3), u2(3), w1(3), w2(3), mass1, mass2
    integer :: trial, count_collisions, count_limited, count_slide
    character(len=32) :: tag
    fluid = .false.
    if (present(in_fluid)) fluid = in_fluid
    config = collision_config_t(restitution=restitution, model=model_name, friction_coefficient=0.2_wp)
    call collision_setup(m, config)
    call stream_seed(stream, 12345_8, stream_id=3)
    worst_p = 0; worst_l = 0; worst_e = -huge(1.0_wp); worst_e_elastic = 0; worst_post = 0
    count_collisions = 0; count_limited = 0; count_slide = 0
    do trial = 1, 2000
      axes1 = semi_axes(ratios(1 + mod(trial, 5)))
      axes2 = semi_axes(ratios(1 + mod((trial - 1) / 5, 5)))
      mass1 = density * 4.0_wp / 3.0_wp * pi * axes1(1) * axes1(2)**2
      mass2 = density * 4.0_wp / 3.0_wp * pi * axes2(1) * axes2(2)**2
      q1 = quaternion_normalise([stream_normal(stream), stream_normal(stream), stream_normal(stream), stream_normal(stream)])
      q2 = quaternion_normalise([stream_normal(stream), stream_normal(stream), stream_normal(stream), stream_normal(stream)])
      theta = pi * stream_uniform(stream)
      phi = pi * (2.0_wp * stream_uniform(stream) - 1.0_wp)
      ! Body 1 at the origin + offset; surface point and outward normal at (theta, phi) (docs/physics.md sec. 0/1).
      y = [axes1(1) * cos(phi), axes1(2) * sin(phi) * cos(theta), axes1(2) * sin(phi) * sin(theta)]
      mb = y / [axes1(1)**2, axes1(2)**2, axes1(2)**2]
      normal = rotate_to_lab(q1, mb / norm2(mb))
      call rigid_body_init(s1, mass1, inertia(mass1, axes1), [1.0e-4_wp, -2.0e-4_wp, 3.0e-5_wp], q1)
      x1 = s1%position + rotate_to_lab(q1, y)
      x2 = x1 + 1.0e-9_wp * normal
      ! Body 2: its surface point whose outward normal is -n: y = -S^2 m / sqrt(m^T S^2 m), m = R2^T n.
      mb = rotate_to_body(q2, normal)
      y = -[axes2(1)**2, axes2(2)**2, axes2(2)**2] * mb / sqrt(sum([axes2(1)**2, axes2(2)**2, axes2(2)**2] * mb**2))
      call rigid_body_init(s2, mass2, inertia(mass2, axes2), x2 - rotate_to_lab(q2, y), q2)
      u1 = 1.0e-3_wp * [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
      u2 = 1.0e-3_wp * [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
      w1 = 30.0_wp * [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
      w2 = 30.0_wp * [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
      s1%velocity = u1; s2%velocity = u2
      s1%angular_velocity_body = rotate_to_body(q1, w1)
      s2%angular_velocity_body = rotate_to_body(q2, w2)
      if (approach_speed(s1, s2, 0.5_wp * (x1 + x2), 0.5_wp * (x1 + x2), normal) <= 0.0_wp) cycle
      added1 = added_inertia_t(); added2 = added_inertia_t()
      if (fluid) then
        added1 = added_inertia_t(3.0_wp * mass1 * random3(stream), 3.0_wp * s1%inertia_body * random3(stream))
        added2 = added_inertia_t(3.0_wp * mass2 * random3(stream), 3.0_wp * s2%inertia_body * random3(stream))
      end if
      p0 = momentum(s1, added1) + momentum(s2, added2)
      l0 = moment_of_momentum(s1, added1) + moment_of_momentum(s2, added2)
      e0 = kinetic_energy(s1, added1) + kinetic_energy(s2, added2)
      scale_p = norm2(momentum(s1, added1)) + norm2(momentum(s2, added2))
      scale_l = norm2(moment_of_momentum(s1, added1)) + norm2(moment_of_momentum(s2, added2))
      if (fluid) then
        call collide(m, s1, s2, x1, x2, normal, res, added1, added2)
      else
        call collide(m, s1, s2, x1, x2, normal, res)
      end if
      count_collisions = count_collisions + 1
      if (res%regime == regime_elastic_limit) count_limited = count_limited + 1
      if (res%regime == regime_slide) count_slide = count_slide + 1
      worst_p = max(worst_p, norm2(momentum(s1, added1) + momentum(s2, added2) - p0) / scale_p)
      worst_l = max(worst_l, norm2(moment_of_momentum(s1, added1) + moment_of_momentum(s2, added2) - l0) / scale_l)
      worst_e = max(worst_e, (kinetic_energy(s1, added1) + kinetic_energy(s2, added2) - e0) / e0)
      ! Normal restitution: exact for every model unless the elastic limit lowered e.
      if (res%regime /= regime_elastic_limit) worst_post = max(worst_post, &
          abs(res%normal_velocity_after + restitution * res%normal_velocity_before) / abs(res%normal_velocity_before))
      if (restitution == 1.0_wp .and. model_name == 'frictionless') &
          worst_e_elastic = max(worst_e_elastic, abs(kinetic_energy(s1) + kinetic_energy(s2) - e0) / e0)
    end do
    write(tag, '(f3.1)') restitution
    tag = trim(model_name)//'_e'//trim(tag)
    if (fluid) tag = trim(tag)//'_in_fluid'
    write(*, '(a,a,i0,a,i0,a,i0,a,3es10.2)') trim(tag), ': collisions ', count_collisions, ', elastic limit ', &
        count_limited, ', sliding ', count_slide, '; worst dP, dL, dE/E = ', worst_p, worst_l, worst_e
    call check(count_collisions > 500, 'random_'//trim(tag)//'_enough_collisions')
    call check_below(worst_p, 1.0e-13_wp, 'random_'//trim(tag)//'_linear_momentum')
    call check_below(worst_l, 1.0e-13_wp, 'random_'//trim(tag)//'_angular_momentum')
    ! "Never gains energy": round-off allowance 1e-13 of the energy.
    call check_below(worst_e, 1.0e-13_wp, 'random_'//trim(tag)//'_no_energy_gain')
    call check_below(worst_post, 1.0e-10_wp, 'random_'//trim(tag)//'_normal_restitution')
    if (restitution == 1.0_wp .and. model_name == 'frictionless') &
        call check_below(worst_e_elastic, 1.0e-13_wp, 'random_frictionless_e1_conserves_energy')
  end subroutine random_collisions

  !> Uniform random numbers in [0, 1), three of them.
  function random3(stream) result(values)
    type(random_stream_t), intent(inout) :: stream
    real(wp) :: values(3)
    integer :: i
    do i = 1, 3
      values(i) = stream_uniform(stream)
    end do
  end function random3

  !> Linear momentum of a body and its added mass, R (m + M_a) R^T U.
  pure function momentum(body, added) result(p)
    type(rigid_body_t), intent(in) :: body
    type(added_inertia_t), intent(in) :: added
    real(wp) :: p(3)
    p = rotate_to_lab(body%quaternion, (body%mass + added%mass) * rotate_to_body(body%quaternion, body%velocity))
  end function momentum

  !> Angular momentum about the origin of a body and its added mass: X x p + R (I + I_a) Omega_b.
  pure function moment_of_momentum(body, added) result(l)
    type(rigid_body_t), intent(in) :: body
    type(added_inertia_t), intent(in) :: added
    real(wp) :: l(3)
    l = cross(body%position, momentum(body, added)) &
        + rotate_to_lab(body%quaternion, (body%inertia_body + added%inertia) * body%angular_velocity_body)
  end function moment_of_momentum

  pure function semi_axes(aspect_ratio) result(axes)
    real(wp), intent(in) :: aspect_ratio
    real(wp) :: axes(2)
    axes = [r * aspect_ratio**(2.0_wp / 3.0_wp), r * aspect_ratio**(-1.0_wp / 3.0_wp)]
  end function semi_axes

  !> Eq. 12 with b = c.
  pure function inertia(mass, axes) result(moments)
    real(wp), intent(in) :: mass, axes(2)
    real(wp) :: moments(3)
    moments = [0.4_wp * mass * axes(2)**2, 0.2_wp * mass * (axes(1)**2 + axes(2)**2), 0.2_wp * mass * (axes(1)**2 + axes(2)**2)]
  end function inertia

  !> Two calcite spheres (r = 50 um) 50 nm apart approaching at 0.875 mm/s with DLVO (Table 1) and
  !> the paper's collisions, for dt from 1e-9 to 1e-5 s (both integrators): every run ends without
  !> NaN, with no overlap left, with the pair's momentum kept (to round-off) and, at the paper's
  !> e = 0.4, with the pair rebounding or bound; the gap never falls below -(v dt) (one step's travel).
  subroutine sphere_pair_time_steps()
    type(dlvo_config_t) :: dcfg
    type(dlvo_model_t) :: dmodel
    type(collision_config_t) :: ccfg
    type(collision_model_t) :: cmodel
    type(rigid_body_t) :: s1, s2
    type(collision_result_t) :: res
    real(wp) :: m, moment, dt, gap, normal(3), x1(3), x2(3), f1(3), t1(3), f2(3), t2(3), min_gap, p0(3), t_end
    integer :: idt, step, nsteps, scheme, collisions
    logical :: finite
    character(len=32) :: tag
    call dlvo_setup(dmodel, dcfg, r)
    call collision_setup(cmodel, ccfg)
    m = density * 4.0_wp / 3.0_wp * pi * r**3
    moment = 0.4_wp * m * r**2
    do scheme = 1, 2
      do idt = 0, 4
        dt = 10.0_wp**(-9 + idt)
        t_end = 1.5e-4_wp + 2000.0_wp * dt
        nsteps = min(nint(t_end / dt), 400000)
        call rigid_body_init(s1, m, [moment, moment, moment], [0.0_wp, 0.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], &
                             velocity=[0.4375e-3_wp, 0.0_wp, 0.0_wp])
        call rigid_body_init(s2, m, [moment, moment, moment], [2.0_wp * r + 50.0e-9_wp, 1.0e-6_wp, 0.0_wp], &
                             [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], velocity=[-0.4375e-3_wp, 0.0_wp, 0.0_wp])
        p0 = s1%velocity * m + s2%velocity * m
        min_gap = huge(1.0_wp)
        collisions = 0
        finite = .true.
        do step = 1, nsteps
          call sphere_contact(s1, s2, gap, normal, x1, x2)
          min_gap = min(min_gap, gap)
          if (collision_detected(cmodel, gap, approach_speed(s1, s2, x1, x2, normal), dt)) then
            call collide(cmodel, s1, s2, x1, x2, normal, res)
            collisions = collisions + 1
          end if
          call dlvo_pair_forces(dmodel, gap, 1.0_wp, normal, x1, x2, s1%position, s2%position, f1, t1, f2, t2)
          call rigid_body_step(s1, f1, t1, dt, merge(integrator_euler, integrator_verlet, scheme == 1))
          call rigid_body_step(s2, f2, t2, dt, merge(integrator_euler, integrator_verlet, scheme == 1))
          finite = finite .and. all(abs(s1%position) < 1.0_wp) .and. all(s1%velocity == s1%velocity)
          if (.not. finite) exit
        end do
        call sphere_contact(s1, s2, gap, normal, x1, x2)
        write(tag, '(a,i0,a,i0)') merge('euler_ ', 'verlet_', scheme == 1), -9 + idt, '_'
        write(*, '(a,a,es10.2,a,i0,a,es11.3,a,es11.3)') 'sphere pair dt = ', '', dt, ' s: collisions ', collisions, &
            ', min gap ', min_gap, ' m, final gap ', gap
        call check(finite, 'pair_dt_1e'//trim(tag)//'finite')
        call check(collisions >= 1, 'pair_dt_1e'//trim(tag)//'collided')
        call check_below(-gap, 0.0_wp, 'pair_dt_1e'//trim(tag)//'no_overlap_at_end')
        call check_below(-min_gap, 0.875e-3_wp * dt + 1.0e-15_wp, 'pair_dt_1e'//trim(tag)//'overlap_below_one_step')
        call check_below(norm2(s1%velocity * m + s2%velocity * m - p0), 1.0e-12_wp * norm2(m * s1%velocity) + 1.0e-25_wp, &
                         'pair_dt_1e'//trim(tag)//'momentum')
      end do
    end do
  end subroutine sphere_pair_time_steps

  !> Exact closest points of two spheres of radius r.
  pure subroutine sphere_contact(s1, s2, gap, normal, x1, x2)
    type(rigid_body_t), intent(in) :: s1, s2
    real(wp), intent(out) :: gap, normal(3), x1(3), x2(3)
    real(wp) :: d(3)
    d = s2%position - s1%position
    normal = d / norm2(d)
    gap = norm2(d) - 2.0_wp * r
    x1 = s1%position + r * normal
    x2 = s2%position - r * normal
  end subroutine sphere_contact
end program test_collision
