! checks: 5
!> The squeeze film of two needles resolved by the immersed boundary (docs/studies/validation.md,
!> "Lubrication", needles and disks; module spheroid_squeeze_case), the fast subset: two needles of
!> aspect 5 (volume-equivalent radius 4 cells) crossed at right angles, equator to equator, approaching
!> along the common normal at fixed speed, the placement held at gaps of 3 and 1 cells, steady Stokes
!> flow. Reference: the near-contact resistance of the sub-grid model at the closest points (module
!> lubrication), whose leading term is the Reynolds squeeze film of the gap h + x.K.x/2,
!> F = 12 pi mu v_n / (h tr K sqrt(det K)) (Reynolds 1886; for crossed needles K is isotropic,
!> (1/b + b/a^2) I, as for crossed cylinders, the sphere-on-plane film of Chan & Horn 1985).
!>  - the reduced radius the model takes from the curvatures at the closest points is that of the
!>    Reynolds film, R_eff = 1 / (1/b + b/a^2) (1e-6), and the closest points have the placed gap;
!>  - the rise of the resolved force from 3 to 1 cell is within 30% of the model's (R(1) - R(3)) 2U
!>    (measured +11.5% in this 32^3 box, +11.2% from 4 to 1 cell in the bench's 52 x 44^2: the grid
!>    carries the crossed needles' squeeze force down to a cell as it does the spheres'; a reduced
!>    radius wrong by a factor sqrt(2) moves the model's rise by about 2 and fails).
program test_immersed_spheroid_squeeze
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use spheroid_squeeze_case, only: spheroid_squeeze_case_t, spheroid_squeeze_result_t, run_spheroid_squeeze
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  type(spheroid_squeeze_case_t) :: case
  type(spheroid_squeeze_result_t) :: wide, near
  real(wp) :: a, b

  call parallel_start()
  call test_start('immersed_spheroid_squeeze')
  case%configuration = 'crossed'
  case%radius_cells = 4.0_wp
  case%cells = [32, 32, 32]
  case%run%steady_tolerance = 2.0e-6_wp
  case%gap_cells = 3.0_wp
  call run_spheroid_squeeze(case, wide)
  case%gap_cells = 1.0_wp
  call run_spheroid_squeeze(case, near)

  a = near%semi_axes(1)
  b = near%semi_axes(2)
  call check_close(near%geometry%reduced_radius, 1.0_wp / (1.0_wp / b + b / a**2), 1.0e-6_wp, &
                   'crossed_needles_reduced_radius_reynolds')
  call check_close(near%gap, near%resolved%cell, 1.0e-9_wp, 'closest_points_gap_is_placed_gap')
  call check(wide%resolved%steady .and. near%resolved%steady, 'steady_state_reached')
  call check_below(near%reynolds, 1.0e-4_wp, 'stokes_regime')
  print '(a,2es11.4,a,2es11.4,a,2(1x,i0))', 'crossed needles at 3 and 1 cells: resolved', wide%resolved%force, &
      near%resolved%force, ' N, model', wide%model_force, near%model_force, ' N, steps', wide%resolved%steps, &
      near%resolved%steps
  call check_close(near%resolved%force - wide%resolved%force, near%model_force - wide%model_force, 0.3_wp, &
                   'resolved_rise_vs_model_rise')
  call test_finish()
end program test_immersed_spheroid_squeeze
