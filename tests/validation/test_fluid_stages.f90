! ranks: 1
! checks: 26
!> The staged fluid step on one rank (checks in fluid_stage_checks; the 2-rank program is
!> test_fluid_stages_two_ranks).
program test_fluid_stages
  use parallel_env, only: parallel_start
  use fluid_stage_checks, only: run_fluid_stage_checks
  use test_framework, only: test_start, test_finish
  implicit none
  call parallel_start()
  call test_start('fluid_stages')
  call run_fluid_stage_checks('_1_rank')
  call test_finish()
end program test_fluid_stages
