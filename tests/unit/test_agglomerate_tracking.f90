! checks: 34
!> Unit tests of agglomerate_tracking and the clusters of its bonds (docs/theory.md, "Agglomerates"),
!> with calcite spheres of radius r and the paper's DLVO model (Table 1) in a periodic box of side L:
!>  - three spheres at rest in a line along x across the periodic boundary, gaps h0 = 5 nm (the vdW
!>    cut-off, where U(h0) < 0: checked), so E = U(h0) < U_b and h0 <= h_r: two bonds, two
!>    formation events at t = 0 with gap h0 and the closest points on the line, at the poles of the
!>    paper's parametrisation (a cos phi, b sin phi cos theta, b sin phi sin theta): phi = 0 on the
!>    first body (its symmetry axis, body x, points at the second) and pi on the second (identity
!>    orientations). The chain's centres are s = 2 r + h0 apart, so R_g^2 = 2 s^2 / 3 over the centres
!>    and 2 s^2 / 3 + 3 r^2 / 5 with the spheres' own gyration (the second moment of a ball, 3 r^2 / 5);
!>  - a pair at rest 400 nm apart (beyond the range h_r = 60 / kappa, 182 nm): not bonded; a pair
!>    20 nm apart approaching at 1 m/s (mu v^2 / 2 far above the well's depth): not bonded;
!>  - the whole system moved by +0.7 s along x (the chain's first body crosses the boundary, its
!>    wraps change): the bonds carried (no event), each image equal to the minimum image of the moved
!>    bodies, R_g unchanged;
!>  - the chain's third body moved 300 nm further (beyond h_r, within the DLVO cut-off, so the pair
!>    keeps its record): one breakage event (kind 2) for the pair (2, 3) at that gap; then the first
!>    body moved 2 um away (the pair loses its record): a breakage reported at its last gap h0;
!>  - the rule is blind to the sign of v_n, the events report it: two spheres 20 nm apart with the
!>    upper one moving along the line of centres at speed w, the critical speed v_c from
!>    mu v_c^2 / 2 = U_b(20 nm) (escape_energy at the pair's chi_eta, mu = m / 2): receding at
!>    0.9 v_c a bond forms with normal speed -0.9 v_c (< 0 receding); approaching at 0.9 v_c at the
!>    same gap it stays (no event); approaching at 1.1 v_c it breaks with normal speed +1.1 v_c at the
!>    same gap, the current values. So a pair that recedes, turns and comes back within the well
!>    forms and breaks at mirror states (docs/theory.md, "Agglomerates", reading the events);
!>  - contact episodes counted per species pair: (1,1), (1,2), (2,2) in the order of species_pair_index.
program test_agglomerate_tracking
  use agglo_kinds, only: wp, i8
  use config_dlvo, only: dlvo_config_t
  use physical_constants, only: pi
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler
  use dlvo, only: dlvo_setup, dlvo_energy, dlvo_range, escape_energy
  use particle_system, only: particle_models_t, particle_system_t, particle_system_create, particle_system_interact, &
                             particle_interaction_gap
  use agglomerates, only: agglomerates_t, agglomerates_analyse, bond_image
  use agglomerate_tracking, only: agglomerate_tracker_t, agglomerate_tracker_create, agglomerate_tracker_update, &
                                  agglomerate_bonds, agglomerate_take_events, agglomerate_count_contact, &
                                  bond_event_t, species_pair_index, species_pairs, event_formed, event_broken
  use test_framework, only: test_start, test_finish, check, check_close, check_equal
  implicit none
  real(wp), parameter :: r = 50.0e-6_wp, density = 2710.0_wp, box = 1.0e-3_wp, h0 = 5.0e-9_wp
  real(wp), parameter :: s = 2.0_wp * r + h0
  integer, parameter :: n = 7

  call test_start('agglomerate_tracking')
  call chain_and_free_pairs()
  call species_counts()
  call mirror_states()
  call test_finish()

contains

  type(particle_models_t) function dlvo_models() result(models)
    models%dlvo = .true.
    call dlvo_setup(models%dlvo_model, dlvo_config_t(), r)
    models%integrator = integrator_euler
    models%interaction_gap = particle_interaction_gap(models)
  end function dlvo_models

  !> The seven bodies at rest (x shifted by shift, unwrapped), body 7 approaching body 6 at speed.
  subroutine build_system(system, shift, third_away)
    type(particle_system_t), intent(out) :: system
    real(wp), intent(in) :: shift
    logical, intent(in) :: third_away
    type(spheroid_t) :: shapes(n)
    type(rigid_body_t) :: bodies(n)
    real(wp) :: centres(3, n), velocities(3, n)
    integer :: i
    shapes = make_spheroid('sphere', r, density)
    centres(:, 1) = [box - 0.6_wp * s, 0.5_wp * box, 0.5_wp * box]     ! the chain, across x = L
    centres(:, 2) = [0.4_wp * s, 0.5_wp * box, 0.5_wp * box]
    centres(:, 3) = [1.4_wp * s, 0.5_wp * box, 0.5_wp * box]
    if (third_away) centres(1, 3) = centres(1, 3) + 300.0e-9_wp
    centres(:, 4) = [0.5_wp * box, 0.2_wp * box, 0.5_wp * box]        ! 400 nm apart
    centres(:, 5) = centres(:, 4) + [0.0_wp, 2.0_wp * r + 400.0e-9_wp, 0.0_wp]
    centres(:, 6) = [0.5_wp * box, 0.5_wp * box, 0.2_wp * box]        ! 20 nm apart, approaching
    centres(:, 7) = centres(:, 6) + [0.0_wp, 0.0_wp, 2.0_wp * r + 20.0e-9_wp]
    velocities = 0.0_wp
    velocities(3, 7) = -1.0_wp
    centres(1, :) = centres(1, :) + shift
    do i = 1, n
      call rigid_body_of_spheroid(bodies(i), shapes(i), centres(:, i), [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], &
                                  velocities(:, i))
    end do
    call particle_system_create(system, shapes, bodies, dlvo_models(), box_length=[box, box, box])
    call particle_system_interact(system, 1.0e-7_wp)
  end subroutine build_system

  subroutine chain_and_free_pairs()
    type(particle_system_t) :: system
    type(agglomerate_tracker_t) :: tracker
    type(agglomerates_t) :: clusters
    type(bond_event_t), allocatable :: events(:)
    real(wp) :: rg_expected
    integer :: b
    logical :: images_true
    call build_system(system, 0.0_wp, .false.)
    call check(dlvo_energy(system%models%dlvo_model, h0, 1.0_wp) < 0.0_wp .and. &
               dlvo_range(system%models%dlvo_model) < 400.0e-9_wp, 'precondition: U(h0) < 0 and h_r < 400 nm')
    call agglomerate_tracker_create(tracker, system, [1, 1, 1, 1, 1, 2, 2], 2)
    call agglomerate_tracker_update(tracker, system, 0.0_wp)
    call check_equal(size(tracker%bonds), 2, 'two bonds: the chain')
    call check(all(tracker%bonds%first == [1, 2]) .and. all(tracker%bonds%second == [2, 3]), 'bonds (1,2) and (2,3)')
    call check(all(tracker%bonds(1)%image == [1, 0, 0]) .and. all(tracker%bonds(2)%image == 0), &
               'bond (1,2) across x = L: body 2 one period on')
    call agglomerate_take_events(tracker, events)
    call check_equal(size(events), 2, 'two events')
    call check(all(events%kind == event_formed) .and. all(abs(events%time) <= 0.0_wp), 'formed at t = 0')
    call check_close(events(1)%gap, h0, 1.0e-6_wp, 'event gap = h0')
    call check_close(events(2)%phi(2), pi, 1.0e-6_wp, 'phi on the second body = pi')
    call check(all(abs(events%phi(1)) < 1.0e-6_wp), 'phi on the first body = 0')
    call check(all(abs(events%normal_speed) < 1.0e-12_wp), 'at rest: normal speed 0')
    call check_equal(tracker%pending, 0, 'events taken')

    call agglomerates_analyse(system%shapes, system%bodies, system%box_length, agglomerate_bonds(tracker), clusters)
    call check_equal(clusters%clusters, 5, 'five clusters: the chain and four singletons')
    call check(all(clusters%cluster_size == [3, 1, 1, 1, 1]), 'sizes (3, 1, 1, 1, 1)')
    rg_expected = sqrt(2.0_wp * s**2 / 3.0_wp + 0.6_wp * r**2)
    call check_close(clusters%radius_of_gyration(1), rg_expected, 1.0e-9_wp, 'R_g of the chain across x = L')
    call check_close(clusters%radius_of_gyration_centres(1), sqrt(2.0_wp / 3.0_wp) * s, 1.0e-9_wp, &
                     'R_g of the chain''s centres')

    ! Moved by 0.7 s: bodies 1 and 2 cross x = L (their wraps change), the bonds stay and are carried.
    ! (The system rebuilt with the moved bodies: its wraps are the crossings since the tracker's last look.)
    call build_system(system, 0.7_wp * s, .false.)
    call agglomerate_tracker_update(tracker, system, 1.0e-6_wp)
    call check(system%wraps(1, 1) == 1_i8, 'precondition: the moved chain crossed the boundary')
    call check(size(tracker%bonds) == 2 .and. tracker%pending == 0, 'moved: the bonds kept, no event')
    images_true = .true.
    do b = 1, size(tracker%bonds)
      associate (bond => tracker%bonds(b))
        images_true = images_true .and. all(bond%image == bond_image(system%bodies(bond%first)%position, &
                                                                     system%bodies(bond%second)%position, system%box_length))
      end associate
    end do
    call check(images_true, 'carried images = the minimum images after the crossing')
    call agglomerates_analyse(system%shapes, system%bodies, system%box_length, agglomerate_bonds(tracker), clusters)
    call check_close(clusters%radius_of_gyration(1), rg_expected, 1.0e-9_wp, 'moved: R_g unchanged')

    ! The third body 300 nm further: the bond (2,3) breaks.
    call build_system(system, 0.7_wp * s, .true.)
    call agglomerate_tracker_update(tracker, system, 2.0e-6_wp)
    call agglomerate_take_events(tracker, events)
    call check_equal(size(events), 1, 'one event')
    call check(events(1)%kind == event_broken .and. all(events(1)%pair == [2, 3]), 'bond (2,3) broken')
    call check_close(events(1)%gap, h0 + 300.0e-9_wp, 1.0e-6_wp, 'broken at gap h0 + 300 nm')
    call check(size(tracker%bonds) == 1 .and. tracker%formed == 2_i8 .and. tracker%broken == 1_i8, &
               'one bond left; 2 formed, 1 broken')

    ! The first body 2 um away (beyond the DLVO cut-off: the pair (1,2) loses its record): broken,
    ! reported with the last values it was seen with (gap h0).
    call build_system(system, 0.7_wp * s, .false.)
    system%bodies(1)%position(1) = system%bodies(1)%position(1) - 2.0e-6_wp
    call particle_system_interact(system, 1.0e-7_wp)
    call agglomerate_tracker_update(tracker, system, 3.0e-6_wp)
    call agglomerate_take_events(tracker, events)
    call check(size(events) == 2 .and. size(tracker%bonds) == 1, 'record lost: (1,2) broken, (2,3) formed again')
    call check(events(1)%kind == event_broken .and. all(events(1)%pair == [1, 2]) .and. &
               abs(events(1)%gap - h0) < 1.0e-15_wp, 'record lost: reported at its last gap h0')
  end subroutine chain_and_free_pairs

  subroutine species_counts()
    type(particle_system_t) :: system
    type(agglomerate_tracker_t) :: tracker
    integer :: pairs(2, 3)
    call build_system(system, 0.0_wp, .false.)
    call agglomerate_tracker_create(tracker, system, [1, 1, 1, 1, 1, 2, 2], 2)
    pairs = species_pairs(2)
    call check(all(pairs(:, 1) == [1, 1]) .and. all(pairs(:, 2) == [1, 2]) .and. all(pairs(:, 3) == [2, 2]), &
               'species pairs (1,1), (1,2), (2,2)')
    call check(species_pair_index(3, 2, 3) == 5 .and. species_pair_index(3, 3, 1) == 3 .and. &
               species_pair_index(3, 3, 3) == 6, 'species_pair_index of three species')
    call agglomerate_count_contact(tracker, 1, 2)
    call agglomerate_count_contact(tracker, 6, 1)
    call agglomerate_count_contact(tracker, 7, 6)
    call agglomerate_count_contact(tracker, 2, 7)
    call check(all(tracker%collisions == [1_i8, 2_i8, 1_i8]), 'episodes per species pair (1, 2, 1)')
  end subroutine species_counts

  !> Two spheres gap h apart along z, the upper one moving at w along +z (w > 0: receding).
  subroutine two_spheres(system, h, w)
    type(particle_system_t), intent(out) :: system
    real(wp), intent(in) :: h, w
    type(spheroid_t) :: shapes(2)
    type(rigid_body_t) :: bodies(2)
    real(wp) :: centre(3)
    shapes = make_spheroid('sphere', r, density)
    centre = [0.5_wp * box, 0.5_wp * box, 0.3_wp * box]
    call rigid_body_of_spheroid(bodies(1), shapes(1), centre, [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
    call rigid_body_of_spheroid(bodies(2), shapes(2), centre + [0.0_wp, 0.0_wp, 2.0_wp * r + h], &
                                [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, w])
    call particle_system_create(system, shapes, bodies, dlvo_models(), box_length=[box, box, box])
    call particle_system_interact(system, 1.0e-7_wp)
  end subroutine two_spheres

  subroutine mirror_states()
    real(wp), parameter :: h = 20.0e-9_wp
    type(particle_system_t) :: system
    type(agglomerate_tracker_t) :: tracker
    type(bond_event_t), allocatable :: events(:)
    real(wp) :: critical, mu
    call two_spheres(system, h, 0.0_wp)
    call check(size(system%pairs) == 1 .and. system%pairs(1)%active, 'mirror: precondition, one current pair record')
    mu = 0.5_wp * system%bodies(1)%mass
    critical = sqrt(2.0_wp * escape_energy(system%models%dlvo_model, h, system%pairs(1)%dlvo%chi_eta) / mu)
    call agglomerate_tracker_create(tracker, system, [1, 1], 1)
    call two_spheres(system, h, 0.9_wp * critical)
    call agglomerate_tracker_update(tracker, system, 0.0_wp)
    call agglomerate_take_events(tracker, events)
    call check(size(events) == 1 .and. size(tracker%bonds) == 1, 'mirror: receding below v_c, one bond formed')
    call check_close(events(1)%normal_speed, -0.9_wp * critical, 1.0e-9_wp, 'mirror: formed receding, v_n = -0.9 v_c')
    call two_spheres(system, h, -0.9_wp * critical)
    call agglomerate_tracker_update(tracker, system, 1.0e-6_wp)
    call check(size(tracker%bonds) == 1 .and. tracker%pending == 0, 'mirror: approaching at 0.9 v_c, the bond kept')
    call two_spheres(system, h, -1.1_wp * critical)
    call agglomerate_tracker_update(tracker, system, 2.0e-6_wp)
    call agglomerate_take_events(tracker, events)
    call check(size(events) == 1 .and. size(tracker%bonds) == 0, 'mirror: approaching above v_c, broken')
    call check(events(1)%kind == event_broken .and. abs(events(1)%normal_speed - 1.1_wp * critical) <= &
               1.0e-9_wp * critical .and. abs(events(1)%gap - h) <= 1.0e-6_wp * h, &
               'mirror: broken approaching at the same gap, v_n = +1.1 v_c (the current values)')
  end subroutine mirror_states
end program test_agglomerate_tracking
