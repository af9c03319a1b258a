! checks: 8
!> Convergence of the implicit ghost rows (the immersed-boundary validation ladder, rung 2;
!> docs/studies/validation.md): needles and disks of aspect 5 (volume-equivalent radius 0.1 mm in a 1 mm box, the
!> disk 4.4 cells thick) at 16 random orientations and positions each, with random rigid motion, at
!> 64^3, starting from a smooth field: the Jacobi sweeps of the pure-mirror ghost rows reach 1e-12 of
!> the velocity scale within 10 sweeps (the bound of docs/studies/validation.md; measured 7 at most from
!> 64^3 to 256^3, make validate). The 128^3 and 256^3 rows are in `make validate`.
program test_immersed_sweeps
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use immersed_sweep_survey, only: sweep_survey_t, run_sweep_survey
  use test_framework, only: test_start, test_finish, check, check_below
  implicit none
  character(len=8), parameter :: shapes(2) = [character(len=8) :: 'needle', 'disk']
  type(sweep_survey_t) :: survey
  integer :: s

  call parallel_start()
  call test_start('immersed_sweeps')
  do s = 1, size(shapes)
    survey%shape = shapes(s)
    survey%cells = 64
    survey%placements = 16
    call run_sweep_survey(survey)
    print '(a,a,f6.2,a,f5.1,a,i0,a,es9.2,a,f8.0)', trim(shapes(s)), ': thin dimension ', survey%thin_cells, &
        ' cells, sweeps mean ', survey%mean_sweeps, ' max ', survey%max_sweeps, ', residual ', survey%max_residual, &
        ', ghosts ', survey%mean_ghosts
    call check(survey%thin_cells > 4.0_wp, trim(shapes(s))//'_at_least_4_cells_thick')
    call check(survey%mean_ghosts > 1000.0_wp, trim(shapes(s))//'_has_ghost_rows')
    call check_below(real(survey%max_sweeps, wp), 10.0_wp, trim(shapes(s))//'_random_orientations_converge_in_10_sweeps')
    call check_below(survey%max_residual, 1.0e-12_wp, trim(shapes(s))//'_residual_below_1e-12')
  end do
  call test_finish()
end program test_immersed_sweeps
