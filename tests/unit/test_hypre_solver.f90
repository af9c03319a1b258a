! checks: 117
!> Tests of hypre_solver on one rank (the same checks as test_hypre_solver_ranks, which runs them
!> on two): every method x preconditioner on the Crank-Nicolson Helmholtz rows and on rows with
!> immersed-boundary ghost rows, value updates, and non-convergence reported as a status.
program test_hypre_solver
  use parallel_env, only: parallel_start
  use hypre_solver_checks, only: run_hypre_solver_checks
  use test_framework, only: test_start, test_finish
  implicit none
  call parallel_start()
  call test_start('hypre_solver')
  call run_hypre_solver_checks()
  call test_finish()
end program test_hypre_solver
