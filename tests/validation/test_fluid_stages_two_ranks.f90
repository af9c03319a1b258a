! ranks: 2
!> The staged fluid step on two ranks (checks in fluid_stage_checks), and the Taylor-Green orders
!> of the incremental pressure scheme (test_fluid_solver has them for the default scheme).
program test_fluid_stages_two_ranks
  use parallel_env, only: parallel_start
  use fluid_stage_checks, only: run_fluid_stage_checks
  use test_framework, only: test_start, test_finish
  implicit none
  call parallel_start()
  call test_start('fluid_stages_two_ranks')
  call run_fluid_stage_checks('_2_ranks')
  call test_finish()
end program test_fluid_stages_two_ranks
