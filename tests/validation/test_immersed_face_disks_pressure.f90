! checks: 3
!> Two disks face to face half a cell apart, resolved by the immersed boundary (docs/theory.md,
!> "Known limit: disks face to face within about a cell"; module spheroid_squeeze_case): aspect 5,
!> volume-equivalent radius 6.43 cells (4.4 cells thick), axes along x, approaching along x at fixed
!> speed, the placement held, explicit diffusion at nu dt/dx^2 = 0.06, implicit ghost rows, in a
!> 28 x 32^2 box (measured: 7.17e-12 N at 4 cells, 4.05e-11 N at 0.5 cell, 467 and 235 steps).
!>  - with the pressure-free projection (pressure_scheme 'non_incremental', the decks' default) the
!>    flow reaches a steady state (relative change of the force below 1e-5 a step) with a force
!>    resisting the approach. With the incremental pressure the same case grows by about 5% a step
!>    from the first steps and stops on NaN (the old pressure's gradient in the predictor, read by
!>    both faces' ghost rows across the gap, feeds the next increment): so this check fails if the
!>    squeeze case's pressure scheme is not passed to the fluid.
!>  - the steady force lies below the sub-grid model's R(h) 2U (the grid does not resolve a half-cell
!>    film; measured 0.19 of the model in the bench's 52 x 44^2 box) and above the force of the same
!>    pair 4 cells apart in this box (the film's force rises as the gap closes).
program test_immersed_face_disks_pressure
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use spheroid_squeeze_case, only: spheroid_squeeze_case_t, spheroid_squeeze_result_t, run_spheroid_squeeze
  use test_framework, only: test_start, test_finish, check, check_below
  implicit none
  type(spheroid_squeeze_case_t) :: case
  type(spheroid_squeeze_result_t) :: wide, near

  call parallel_start()
  call test_start('immersed_face_disks_pressure')
  case%configuration = 'face'
  case%radius_cells = 6.43_wp
  case%cells = [28, 32, 32]
  case%run%steady_tolerance = 1.0e-5_wp
  case%run%max_steps = 3000
  case%run%pressure_scheme = 'non_incremental'
  case%gap_cells = 4.0_wp
  call run_spheroid_squeeze(case, wide)
  case%gap_cells = 0.5_wp
  call run_spheroid_squeeze(case, near)
  print '(a,2es11.4,a,es11.4,a,2(1x,i0))', 'face disks at 4 and 0.5 cells: resolved', wide%resolved%force, &
      near%resolved%force, ' N, model at 0.5', near%model_force, ' N, steps', wide%resolved%steps, near%resolved%steps
  call check(wide%resolved%steady .and. near%resolved%steady, 'steady_state_reached_half_cell_apart')
  call check(near%resolved%force > wide%resolved%force, 'film_force_rises_as_the_gap_closes')
  call check_below(near%resolved%force, near%model_force, 'film_force_below_the_subgrid_model')
  call test_finish()
end program test_immersed_face_disks_pressure
