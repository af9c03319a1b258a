! ranks: 2
! checks: 117
!> Tests of hypre_solver on two ranks (z slabs): the checks of test_hypre_solver, with the
!> system's rows split across the ranks, the ghost rows' mirror cubes crossing the slab
!> boundary, and the distributed solution compared with a whole-box solve on one rank.
program test_hypre_solver_ranks
  use parallel_env, only: parallel_start
  use hypre_solver_checks, only: run_hypre_solver_checks
  use test_framework, only: test_start, test_finish
  implicit none
  call parallel_start()
  call test_start('hypre_solver_ranks')
  call run_hypre_solver_checks()
  call test_finish()
end program test_hypre_solver_ranks
