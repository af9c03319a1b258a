! ranks: 2
!> Unit tests of checkpoint_files on 2 ranks: write-then-rename, newest complete checkpoint,
!> pruning beyond checkpoints_kept, and a killed run (a .tmp file left behind) that is ignored.
!> Reference: the file names and contents the test itself wrote.
program test_checkpoint_files
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use run_directory, only: prepare_run_directory
  use checkpoint_files, only: checkpoint_begin, checkpoint_commit, newest_checkpoint, checkpoint_path
  use hdf5_io, only: h5_file_t, h5_create, h5_open, h5_close, h5_write_array, h5_read_array, h5_write_slab, &
                     h5_read_slab, hdf5_io_finalize
  use file_system, only: file_exists
  use parallel_env, only: parallel_start, my_rank, n_ranks, barrier
  use test_framework, only: test_start, test_finish, check
  implicit none
  type(agglo_config_t) :: cfg
  type(h5_file_t) :: file
  character(len=:), allocatable :: newest
  real(wp) :: field(4, 3, 2), back(4, 3, 2)
  integer(i8) :: step
  integer :: status

  call parallel_start()
  call test_start('checkpoint_files')
  cfg%output%directory = 'test_checkpoint_files_run'
  cfg%run%overwrite = .true.
  if (my_rank == 0) call execute_command_line('rm -rf test_checkpoint_files_run', exitstat=status)
  call barrier()
  call prepare_run_directory(cfg)

  call check(newest_checkpoint() == '', 'no_checkpoint_gives_empty_path')

  field = real(my_rank + 1, wp) / 7.0_wp
  call write_checkpoint(10_i8, 2)
  call write_checkpoint(20_i8, 2)
  newest = newest_checkpoint()
  call check(newest == checkpoint_path(20_i8), 'newest_is_highest_step', newest)
  call check(index(newest, 'checkpoints/checkpoint_0000000020.h5') > 0, 'name_has_10_digit_step', newest)
  call check(.not. file_exists(checkpoint_path(20_i8, temporary=.true.)), 'tmp_renamed_on_commit')

  ! A killed run: checkpoint 30 written to its temporary name, never completed (killed before the
  ! close that renames it), so the .tmp file stays behind.
  call h5_create(file, checkpoint_path(30_i8, temporary=.true.))
  call h5_write_array(file, 'step', 30_i8)
  call h5_close(file)
  call barrier()
  call check(file_exists(checkpoint_path(30_i8, temporary=.true.)), 'killed_run_leaves_tmp')
  newest = newest_checkpoint()
  call check(newest == checkpoint_path(20_i8), 'killed_run_tmp_ignored', newest)

  ! The restart reads what the newest complete checkpoint holds (bit for bit).
  call h5_open(file, newest, writable=.false.)
  call h5_read_array(file, 'step', step)
  call h5_read_slab(file, 'u', back, 2 * my_rank, [4, 3, 2 * n_ranks])
  call h5_close(file)
  call check(step == 20_i8 .and. all(back == field), 'newest_checkpoint_contents')

  ! The next commit (kept = 2) prunes checkpoint 10 and the stale .tmp of 30, keeps 20 and 40.
  call write_checkpoint(40_i8, 2)
  call check(.not. file_exists(checkpoint_path(10_i8)) .and. file_exists(checkpoint_path(20_i8)) .and. &
             file_exists(checkpoint_path(40_i8)), 'prune_keeps_newest_2')
  call check(.not. file_exists(checkpoint_path(30_i8, temporary=.true.)), 'stale_tmp_removed_on_commit')
  call write_checkpoint(50_i8, 1)
  call check(.not. file_exists(checkpoint_path(20_i8)) .and. .not. file_exists(checkpoint_path(40_i8)) .and. &
             file_exists(checkpoint_path(50_i8)), 'prune_keeps_newest_1')
  ! Steps above 2**31 (integer(i8) step counters) name files too.
  call write_checkpoint(3000000000_i8, 1)
  call check(newest_checkpoint() == checkpoint_path(3000000000_i8), 'i8_step_names_checkpoint')
  ! The default-integer interface gives the same names.
  call checkpoint_begin(7, file)
  call checkpoint_commit(file, 7, 5)
  call check(file_exists(checkpoint_path(7_i8)), 'default_integer_step_interface')

  call barrier()
  if (my_rank == 0) call execute_command_line('rm -rf test_checkpoint_files_run', exitstat=status)
  call hdf5_io_finalize()
  call test_finish()

contains

  subroutine write_checkpoint(step_number, kept)
    integer(i8), intent(in) :: step_number
    integer, intent(in) :: kept
    call checkpoint_begin(step_number, file)
    call h5_write_array(file, 'step', step_number)
    call h5_write_slab(file, 'u', field, 2 * my_rank, [4, 3, 2 * n_ranks])
    call checkpoint_commit(file, step_number, kept)
  end subroutine write_checkpoint
end program test_checkpoint_files
