! checks: 22
!> Unit tests of the particle system's iterated sequential impulses (several simultaneous contacts,
!> docs/theory.md "Particle system"): Newton's cradles of five touching equal spheres struck from
!> either end (e = 1: the far sphere leaves with the striker's velocity, the others at rest; the
!> reversed cradle needs one sweep per contact), a triangle of three touching spheres struck
!> symmetrically (a mirror-symmetric outcome), and a tetrahedral cluster of ten touching spheres
!> struck obliquely by an eleventh (no approaching contact left within the cap; linear and angular
!> momentum conserved to round-off, energy not gained; with the sweeps capped below what it needs, the
!> contacts left approaching are counted). Touching: surface gaps of 0.5 nm, below the
!> 1 nm detection floor, so every touching pair is a contact of the same step.
program test_multi_contact
  use agglo_kinds, only: wp
  use config_collision, only: collision_config_t
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, linear_momentum, angular_momentum, integrator_euler
  use collision, only: collision_setup, approach_speed, collision_frictionless
  use particle_system, only: particle_models_t, particle_system_t, particle_system_create, particle_system_interact, &
                             particle_system_energy, pair_body_image
  use test_framework, only: test_start, test_finish, check, check_close, check_below, check_equal
  implicit none
  real(wp), parameter :: radius = 50.0e-6_wp, density = 2710.0_wp, gap = 0.5e-9_wp, dt = 1.0e-7_wp
  real(wp), parameter :: v = 1.0e-3_wp                 !< m/s, the striker's speed
  real(wp), parameter :: spacing = 2.0_wp * radius + gap

  call test_start('multi_contact')
  call cradle(1)
  call cradle(-1)
  call triangle()
  call cluster()
  call test_finish()

contains

  !> Models: collisions only (no DLVO), the paper's impulse with restitution e.
  type(particle_models_t) function models_of(restitution) result(models)
    real(wp), intent(in) :: restitution
    models%collisions = .true.
    call collision_setup(models%collision_model, collision_config_t())
    models%collision_model%restitution = restitution
    models%integrator = integrator_euler
  end function models_of

  !> Five spheres in a line along x, e = 1. direction = 1: sphere 1 struck towards +x; direction =
  !> -1: sphere 5 struck towards -x (against the order of the pair list). Either way each wave of
  !> contacts passes the velocity on by one contact: 4 waves of one sweep in one interaction.
  subroutine cradle(direction)
    integer, intent(in) :: direction
    integer, parameter :: n = 5
    type(spheroid_t) :: sphere
    type(rigid_body_t) :: bodies(n)
    type(particle_system_t) :: system
    real(wp) :: p0(3), e0, rest
    integer :: i, striker, leaver
    character(len=8) :: tag
    sphere = make_spheroid('sphere', radius, density)
    do i = 1, n
      call rigid_body_of_spheroid(bodies(i), sphere, [real(i - 1, wp) * spacing, 0.0_wp, 0.0_wp], &
                                  [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    end do
    striker = merge(1, n, direction == 1)
    leaver = merge(n, 1, direction == 1)
    tag = merge('forward ', 'reversed', direction == 1)
    bodies(striker)%velocity = [real(direction, wp) * v, 0.0_wp, 0.0_wp]
    call particle_system_create(system, spread(sphere, 1, n), bodies, models_of(1.0_wp))
    p0 = total_momentum(system)
    e0 = particle_system_energy(system)
    call particle_system_interact(system, dt)
    call check_equal(system%impulse_sweeps_last, n - 1, 'cradle_'//trim(tag)//'_sweeps')
    call check_close(system%bodies(leaver)%velocity(1), real(direction, wp) * v, 1.0e-12_wp, &
                     'cradle_'//trim(tag)//'_last_leaves_at_v')
    rest = 0.0_wp
    do i = 1, n
      if (i /= leaver) rest = max(rest, norm2(system%bodies(i)%velocity))
    end do
    call check_below(rest, 1.0e-12_wp * v, 'cradle_'//trim(tag)//'_others_at_rest')
    call check_below(norm2(total_momentum(system) - p0) / norm2(p0) + abs(particle_system_energy(system) - e0) / e0, &
                     1.0e-13_wp, 'cradle_'//trim(tag)//'_momentum_and_energy')
  end subroutine cradle

  !> Spheres 1 and 2 touching on the x axis, sphere 3 touching both at the apex of the triangle
  !> (xy plane), struck towards the base midpoint (-y) with e = 0.4: contacts 1-3 and 2-3 are hit
  !> at once, and 1-2 is loaded as 1 and 2 are pushed apart. Mirror symmetry about x = 0: u1 and
  !> u2 mirror images, u3 along -y or +y only, no spin about y. The sweeps converge to that state
  !> (the sequential order 1-3 before 2-3 alone would favour body 1).
  subroutine triangle()
    type(spheroid_t) :: sphere
    type(rigid_body_t) :: bodies(3)
    type(particle_system_t) :: system
    type(particle_models_t) :: models
    real(wp) :: asymmetry, p0(3), e0
    sphere = make_spheroid('sphere', radius, density)
    call rigid_body_of_spheroid(bodies(1), sphere, [-0.5_wp * spacing, 0.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    call rigid_body_of_spheroid(bodies(2), sphere, [0.5_wp * spacing, 0.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    call rigid_body_of_spheroid(bodies(3), sphere, [0.0_wp, 0.5_wp * sqrt(3.0_wp) * spacing, 0.0_wp], &
                                [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], velocity=[0.0_wp, -v, 0.0_wp])
    models = models_of(0.4_wp)
    models%collision_model%model = collision_frictionless
    call particle_system_create(system, [sphere, sphere, sphere], bodies, models)
    p0 = total_momentum(system)
    e0 = particle_system_energy(system)
    call particle_system_interact(system, dt)
    associate (u1 => system%bodies(1)%velocity, u2 => system%bodies(2)%velocity, u3 => system%bodies(3)%velocity, &
               w1 => system%bodies(1)%angular_velocity_body, w2 => system%bodies(2)%angular_velocity_body)
      asymmetry = norm2([u1(1) + u2(1), u1(2) - u2(2), u1(3) - u2(3), u3(1), u3(3)]) / v &
                  + radius * norm2([w1(1) - w2(1), w1(2) + w2(2), w1(3) + w2(3)]) / v
      call check(u2(1) > 1.0e-2_wp * v .and. u1(1) < -1.0e-2_wp * v, 'triangle_base_pushed_apart')
    end associate
    call check(system%impulse_sweeps_last > 1 .and. system%approaching_left == 0, 'triangle_iterated_to_rest', &
               'sweeps '//trim(int_string(system%impulse_sweeps_last)))
    call check_below(asymmetry, 1.0e-8_wp, 'triangle_mirror_symmetric')
    call check_below(largest_approach(system), 1.0e-9_wp * v, 'triangle_no_contact_approaching')
    call check_below(norm2(total_momentum(system) - p0) / norm2(p0), 1.0e-14_wp, 'triangle_momentum_conserved')
    call check_below(particle_system_energy(system) - e0, 0.0_wp, 'triangle_energy_not_gained')
  end subroutine triangle

  !> Ten spheres stacked as a tetrahedron (6 + 3 + 1, each touching its close-packed neighbours: 18
  !> contacts), struck by an eleventh touching the corner sphere 1 and moving towards the
  !> cluster's centre with an offset (an oblique, eccentric hit), e = 0.4, the paper's impulse
  !> (tangential slip removed, so the spheres spin).
  subroutine cluster()
    integer, parameter :: n = 11
    type(spheroid_t) :: sphere
    type(rigid_body_t) :: bodies(n)
    type(particle_system_t) :: system
    type(particle_models_t) :: models
    real(wp) :: x(3, n), centre(3), direction(3), aim(3), p0(3), l0(3), e0, h
    integer :: i, j, k, b, contacts
    sphere = make_spheroid('sphere', radius, density)
    h = sqrt(2.0_wp / 3.0_wp) * spacing   ! layer height of close packing
    b = 0
    do k = 0, 2                            ! layers of 6, 3, 1 spheres
      do j = 0, 2 - k
        do i = 0, 2 - k - j
          b = b + 1
          x(:, b) = [(real(i, wp) + 0.5_wp * real(j, wp) + 0.5_wp * real(k, wp)) * spacing, &
                     (real(j, wp) + real(k, wp) / 3.0_wp) * 0.5_wp * sqrt(3.0_wp) * spacing, real(k, wp) * h]
        end do
      end do
    end do
    centre = sum(x(:, 1:10), dim=2) / 10.0_wp
    ! The striker touches sphere 1 on the side away from the centre, a little off the line.
    direction = x(:, 1) - centre + [0.0_wp, 0.3_wp * radius, -0.2_wp * radius]
    direction = direction / norm2(direction)
    x(:, n) = x(:, 1) + spacing * direction
    do b = 1, n
      call rigid_body_of_spheroid(bodies(b), sphere, x(:, b), [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    end do
    aim = centre + [0.0_wp, 0.0_wp, 0.5_wp * radius]
    bodies(n)%velocity = v * (aim - x(:, n)) / norm2(aim - x(:, n))
    call particle_system_create(system, spread(sphere, 1, n), bodies, models_of(0.4_wp))
    contacts = 0
    do b = 1, n - 1
      do j = b + 1, n
        if (norm2(x(:, j) - x(:, b)) < spacing * (1.0_wp + 1.0e-9_wp)) contacts = contacts + 1
      end do
    end do
    call check_equal(contacts, 25, 'cluster_touching_pairs')
    p0 = total_momentum(system)
    l0 = total_angular_momentum(system)
    e0 = particle_system_energy(system)
    call particle_system_interact(system, dt)
    call check(system%impulse_sweeps_last > 1 .and. system%impulse_sweeps_last < system%models%collision_model%max_sweeps &
               .and. system%approaching_left == 0, 'cluster_converged_within_the_cap', &
               'sweeps '//trim(int_string(system%impulse_sweeps_last))//', impulses '// &
               trim(int_string(system%collisions_last)))
    call check_below(largest_approach(system), 1.0e-9_wp * v, 'cluster_no_contact_approaching')
    call check_below(norm2(total_momentum(system) - p0) / norm2(p0), 1.0e-12_wp, 'cluster_linear_momentum')
    call check_below(norm2(total_angular_momentum(system) - l0) / norm2(l0), 1.0e-12_wp, 'cluster_angular_momentum')
    call check_below(particle_system_energy(system) - e0, 1.0e-14_wp * e0, 'cluster_energy_not_gained')
    call check(count([(norm2(system%bodies(b)%velocity) > 1.0e-3_wp * v, b = 1, 10)]) >= 3, 'cluster_struck_spheres_move')
    ! The same hit with the sweeps capped at 3: contacts left approaching, counted (and logged).
    models = models_of(0.4_wp)
    models%collision_model%max_sweeps = 3
    call particle_system_create(system, spread(sphere, 1, n), bodies, models)
    call particle_system_interact(system, dt)
    call check(system%impulse_sweeps_last == 3 .and. system%approaching_left > 0 .and. system%sweep_caps_total == 1 &
               .and. norm2(total_momentum(system) - p0) / norm2(p0) < 1.0e-12_wp, 'cluster_cap_reached_and_counted', &
               'contacts left approaching '//trim(int_string(system%approaching_left)))
  end subroutine cluster

  !> Largest approach speed (m/s, > 0 approaching) of the pairs whose gap is below the detection
  !> floor (the touching pairs), from their closest points: 0 when every contact is at rest or
  !> separating.
  real(wp) function largest_approach(system)
    type(particle_system_t), intent(in) :: system
    integer :: p
    largest_approach = 0.0_wp
    do p = 1, size(system%pairs)
      associate (pair => system%pairs(p))
        if (.not. pair%active) cycle
        if (pair%contact%gap > system%models%collision_model%detection_floor) cycle
        largest_approach = max(largest_approach, approach_speed(system%bodies(pair%first), &
            pair_body_image(system, pair), pair%contact%point1, pair%contact%point2, pair%contact%normal))
      end associate
    end do
  end function largest_approach

  function total_momentum(system) result(p)
    type(particle_system_t), intent(in) :: system
    real(wp) :: p(3)
    integer :: i
    p = 0.0_wp
    do i = 1, system%n
      p = p + linear_momentum(system%bodies(i))
    end do
  end function total_momentum

  function total_angular_momentum(system) result(l)
    type(particle_system_t), intent(in) :: system
    real(wp) :: l(3)
    integer :: i
    l = 0.0_wp
    do i = 1, system%n
      l = l + angular_momentum(system%bodies(i))
    end do
  end function total_angular_momentum

  function int_string(value) result(text)
    integer, intent(in) :: value
    character(len=12) :: text
    write(text, '(i0)') value
  end function int_string

end program test_multi_contact
