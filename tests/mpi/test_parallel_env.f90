! ranks: 2
! checks: 7
!> The agreements of parallel_env on 2 ranks that let a check made by one rank, or by each rank for
!> itself, stop every rank together (error_handling: a collective stop needs every rank to call it):
!> all_ranks (logical and), any_rank (logical or), root_text (rank 0's text everywhere). The ranks
!> pass different values on purpose; each check holds on every rank
!> (test_framework's on_every_rank: a reduction of the test's own, not the routines under test).
program test_parallel_env
  use parallel_env, only: parallel_start, my_rank, n_ranks, all_ranks, any_rank, root_text
  use test_framework, only: test_start, test_finish, check, check_equal, on_every_rank
  implicit none
  character(len=:), allocatable :: shared

  call parallel_start()
  call test_start('parallel_env')
  call check_equal(n_ranks, 2, 'runs_on_two_ranks')

  call check(on_every_rank(all_ranks(.true.)), 'all_ranks_true_when_every_rank_true')
  call check(on_every_rank(.not. all_ranks(my_rank == 0)), 'all_ranks_false_when_one_rank_false')
  call check(on_every_rank(any_rank(my_rank == 1)), 'any_rank_true_when_one_rank_true')
  call check(on_every_rank(.not. any_rank(.false.)), 'any_rank_false_when_every_rank_false')

  if (my_rank == 0) then
    shared = root_text('verdict of rank 0')
  else
    shared = root_text('another text, longer than the one of rank 0')
  end if
  call check(on_every_rank(shared == 'verdict of rank 0' .and. len(shared) == 17), 'root_text_is_rank_0_text', shared)
  if (my_rank == 0) then
    shared = root_text('')
  else
    shared = root_text('rank 1 alone found something')
  end if
  call check(on_every_rank(len(shared) == 0), 'root_text_empty_when_rank_0_passes_empty', shared)
  call test_finish()
end program test_parallel_env
