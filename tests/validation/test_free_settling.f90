! checks: 8
!> A free sphere settling in the periodic box, resolved by the immersed boundary (docs/studies/validation.md,
!> "Free particles"): one sphere per cell is a simple-cubic array, so at steady state its slip
!> velocity is the one at which the array's Stokes drag balances the net weight W:
!>   W = 6 pi mu a K(phi) U_s,   U_s = U_p - U_face (the superficial velocity relative to the sphere,
!> U_face the flux through the box's x-face over its area, a plane the sphere never cuts), with the
!> Zick & Homsy (1982, J. Fluid Mech. 115, 13, Table 2) K = 4.292 at phi = 0.125. The same cell,
!> D/dx = 8.06 (13^3), as the fixed-sphere array of test_immersed_stokes (K = 4.2794, -0.29%,
!> docs/studies/validation.md "Immersed boundary"): the free sphere's K must agree with the fixed array's to
!> 0.5% and with Zick & Homsy to 1%. The gravity path of module resolved_hydrodynamics: the net
!> weight on the sphere and the opposite drive -W / L^3 over the box; the added-mass stabilisation on.
!> Also: the potential-flow added masses the stabilisation uses (sphere k = 1/2; the face-on disk of
!> aspect ratio 5 at the calcite density ratio, added mass / mass = 1.11, Kim & Karrila 1991 ch. 7) and
!> the rotational added inertia (zero for a sphere; for the disk about a diameter a fraction of the
!> disk's own inertia, below 1 at the calcite ratio: the rotation stays explicitly stable).
program test_free_settling
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid
  use stokes_resistance, only: spheroid_added_mass_coefficients
  use resolved_hydrodynamics, only: rotational_added_inertia
  use settling_sphere_case, only: settling_case_t, settling_result_t, run_settling_sphere
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  real(wp), parameter :: zick_homsy_0125 = 4.292_wp   ! Zick & Homsy 1982, Table 2, phi = 0.125
  real(wp), parameter :: fixed_array_13 = 4.2794_wp   ! the fixed sphere at 13^3 (docs/studies/validation.md)
  type(spheroid_t) :: shape, disk
  type(rigid_body_t) :: body
  type(settling_case_t) :: case
  type(settling_result_t) :: result
  real(wp) :: k(2), ratio
  character(len=160) :: text

  call parallel_start()
  call test_start('free_settling')

  ! The coefficients the stabilisation uses.
  k = spheroid_added_mass_coefficients(1.0_wp, 1.0_wp)
  call check_close(k(1), 0.5_wp, 1.0e-10_wp, 'sphere_added_mass_one_half')
  disk = make_spheroid('disk', 50.0e-6_wp, 2710.0_wp, 5.0_wp)
  k = spheroid_added_mass_coefficients(disk%a, disk%b)
  ratio = k(1) * 997.0_wp / 2710.0_wp
  write(text, '(a,f6.3)') 'face-on disk (aspect 5) added mass / mass at 2710/997: ', ratio
  print '(a)', trim(text)
  call check_close(ratio, 1.107_wp, 0.01_wp, 'face_on_disk_added_mass_ratio_potential_flow')
  shape = make_spheroid('sphere', 50.0e-6_wp, 2710.0_wp)
  call check_below(abs(rotational_added_inertia(shape, 997.0_wp)), 1.0e-30_wp, 'sphere_no_rotational_added_inertia')
  call rigid_body_of_spheroid(body, disk, [0.0_wp, 0.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], &
                              [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
  ratio = rotational_added_inertia(disk, 997.0_wp) / body%inertia_body(2)
  write(text, '(a,f6.3)') 'disk (aspect 5) rotational added inertia / inertia about a diameter at 2710/997: ', ratio
  print '(a)', trim(text)
  call check(ratio > 0.1_wp .and. ratio < 1.0_wp, 'disk_rotational_added_inertia_below_own_at_calcite')

  ! The settling sphere at the calcite density ratio (module settling_sphere_case).
  call run_settling_sphere(case, result)
  write(text, '(a,f6.2,a,es10.3,a,f7.4,a,f6.2,a,f6.2,a,i0)') 'settling sphere D/dx ', result%diameter_cells, &
      ' slip ', result%slip, ' m/s K ', result%drag_coefficient, ' vs Z&H ', &
      100 * (result%drag_coefficient / zick_homsy_0125 - 1), '%, vs fixed array ', &
      100 * (result%drag_coefficient / fixed_array_13 - 1), '% steps ', result%steps
  print '(a)', trim(text)
  call check(result%steady, 'settling_sphere_reaches_terminal_velocity')
  call check_close(result%drag_coefficient, fixed_array_13, 0.005_wp, 'settling_sphere_drag_equals_fixed_array_0p5pc')
  call check_close(result%drag_coefficient, zick_homsy_0125, 0.01_wp, 'settling_sphere_drag_zick_homsy_1pc')
  ! No net force on the box (the drive balances the weight): its momentum, the fluid nodes' plus
  ! the sphere's (the fictitious fluid on the sphere's nodes is none of the physical system's),
  ! stays zero.
  write(text, '(a,es10.3)') 'box momentum / (rho_f L^3 slip): ', result%momentum
  print '(a)', trim(text)
  call check_below(abs(result%momentum), 1.0e-6_wp, 'settling_box_momentum_stays_zero')
  call test_finish()
end program test_free_settling
