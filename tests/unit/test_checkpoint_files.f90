! ranks: 2
! checks: 22
!> Unit tests of checkpoint_files on 2 ranks: checkpoint transactions (components write and read their
!> own groups, one commit), write-then-rename, newest valid checkpoint, pruning beyond
!> checkpoints_kept, a killed run (a .tmp file left behind) that is ignored, and damaged checkpoints:
!> a corrupted data byte (caught by the Fletcher-32 checksum), a damaged header (caught by the
!> metadata checksums of the 1.8 file format), a truncated and a zeroed file, and
!> files merely named like the newest checkpoint, each passed over for the previous valid one.
!> Reference: the file names and contents the test itself wrote.
program test_checkpoint_files
  use, intrinsic :: iso_fortran_env, only: int8
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use run_directory, only: prepare_run_directory
  use checkpoint_files, only: checkpoint_t, checkpoint_begin, checkpoint_commit, newest_checkpoint, checkpoint_path, &
                              checkpoint_open_newest, checkpoint_close, checkpoint_is_valid
  use hdf5_files, only: h5_file_t, h5_create, h5_close, h5_exists, h5_finalize
  use hdf5_datasets, only: h5_read_scalar, h5_write_array, h5_read_array, h5_write_slab, h5_read_slab
  use file_system, only: file_exists, rename_file, delete_file
  use parallel_env, only: parallel_start, my_rank, n_ranks, barrier, is_root
  use test_framework, only: test_start, test_finish, check
  implicit none
  type(agglo_config_t) :: cfg
  type(h5_file_t) :: file
  type(checkpoint_t) :: checkpoint
  character(len=:), allocatable :: newest, reason
  real(wp) :: field(4, 3, 2), back(4, 3, 2)
  integer(i8) :: step
  integer :: status
  logical :: ok, renamed

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
  call h5_write_array(file, 'component_a/step', 30_i8)
  call h5_close(file)
  call barrier()
  call check(file_exists(checkpoint_path(30_i8, temporary=.true.)), 'killed_run_leaves_tmp')
  newest = newest_checkpoint()
  call check(newest == checkpoint_path(20_i8), 'killed_run_tmp_ignored', newest)

  ! The restart transaction: each component reads its own group back (bit for bit).
  call checkpoint_open_newest(checkpoint)
  call h5_read_scalar(checkpoint%file, 'component_a/step', step)
  call h5_read_slab(checkpoint%file, 'component_b/u', back, 2 * my_rank, [4, 3, 2 * n_ranks])
  call check(checkpoint%step == 20_i8 .and. step == 20_i8 .and. all(back == field), 'transaction_groups_read_back')
  call check(h5_exists(checkpoint%file, 'checkpoint/complete'), 'commit_marks_complete')
  call checkpoint_close(checkpoint)

  ! The next commit (kept = 2) prunes checkpoint 10 and the stale .tmp of 30, keeps 20 and 40.
  call write_checkpoint(40_i8, 2)
  call check(.not. file_exists(checkpoint_path(10_i8)) .and. file_exists(checkpoint_path(20_i8)) .and. &
             file_exists(checkpoint_path(40_i8)), 'prune_keeps_newest_2')
  call check(.not. file_exists(checkpoint_path(30_i8, temporary=.true.)), 'stale_tmp_removed_on_commit')

  ! Damaged newest checkpoints: each is passed over for checkpoint 20 (kept = 5 from here on).
  call write_checkpoint(50_i8, 5)
  if (is_root()) call damage(checkpoint_path(50_i8), 'flip')
  call barrier()
  newest = newest_checkpoint()
  call check(newest == checkpoint_path(40_i8), 'corrupted_data_byte_caught_by_checksum', newest)
  if (is_root()) call checkpoint_is_valid(checkpoint_path(50_i8), 50_i8, ok, reason)
  if (is_root()) call check(.not. ok .and. index(reason, 'component_b/u') > 0, 'corruption_reason_names_dataset', reason)
  if (is_root()) call damage(checkpoint_path(40_i8), 'truncate')
  call barrier()
  newest = newest_checkpoint()
  call check(newest == checkpoint_path(20_i8), 'truncated_checkpoint_passed_over', newest)
  if (is_root()) call damage(checkpoint_path(20_i8), 'zero')
  call write_checkpoint(60_i8, 5)
  if (is_root()) call damage(checkpoint_path(60_i8), 'zero')
  call barrier()
  newest = newest_checkpoint()
  call check(newest == '', 'zeroed_checkpoints_passed_over_none_left', newest)

  ! Files merely named like a newer checkpoint: a copy of a valid checkpoint under a later step, a
  ! text file, and an HDF5 file without the completion mark.
  call write_checkpoint(70_i8, 5)
  if (is_root()) then
    call copy_file(checkpoint_path(70_i8), checkpoint_path(9999999999_i8))
    call write_text(checkpoint_path(9999999998_i8))
  end if
  call barrier()
  call h5_create(file, checkpoint_path(9999999997_i8))
  call h5_write_array(file, 'component_a/step', 9999999997_i8)
  call h5_close(file)
  newest = newest_checkpoint()
  call check(newest == checkpoint_path(70_i8), 'files_named_like_checkpoints_not_taken', newest)
  ! Pruning counts only checkpoints up to the step committed: the foreign files do not make it
  ! delete the real ones (kept = 1 keeps 80), and are left alone.
  call write_checkpoint(80_i8, 1)
  call check(file_exists(checkpoint_path(80_i8)) .and. .not. file_exists(checkpoint_path(70_i8)) .and. &
             file_exists(checkpoint_path(9999999999_i8)), 'prune_ignores_later_named_files')
  call barrier()   ! every rank has looked before rank 0 cleans up
  if (is_root()) then
    call delete_file(checkpoint_path(9999999999_i8))
    call delete_file(checkpoint_path(9999999998_i8))
    call delete_file(checkpoint_path(9999999997_i8))
  end if
  call barrier()

  ! A damaged header (one byte of a group name): caught by the metadata checksums of the file format.
  call write_checkpoint(90_i8, 5)
  if (is_root()) call damage(checkpoint_path(90_i8), 'header')
  call barrier()
  newest = newest_checkpoint()
  call check(newest == checkpoint_path(80_i8), 'damaged_header_caught_by_checksum', newest)

  ! Steps above 2**31 (integer(i8) step counters) name files too.
  call write_checkpoint(3000000000_i8, 1)
  call check(newest_checkpoint() == checkpoint_path(3000000000_i8), 'i8_step_names_checkpoint')
  ! The default-integer interface gives the same names.
  call checkpoint_begin(checkpoint, 7)
  call checkpoint_commit(checkpoint, 5)
  call check(file_exists(checkpoint_path(7_i8)), 'default_integer_step_interface')
  call barrier()   ! every rank has looked before rank 0 renames it
  if (is_root()) call rename_file(checkpoint_path(7_i8), checkpoint_path(8_i8), renamed)
  call barrier()
  if (is_root()) call checkpoint_is_valid(checkpoint_path(8_i8), 8_i8, ok, reason)
  if (is_root()) call check(.not. ok .and. index(reason, 'holds step 7') > 0, 'renamed_checkpoint_step_mismatch', reason)

  call barrier()
  if (my_rank == 0) call execute_command_line('rm -rf test_checkpoint_files_run', exitstat=status)
  call h5_finalize()
  call test_finish()

contains

  !> One checkpoint transaction with two components, each writing its own group.
  subroutine write_checkpoint(step_number, kept)
    integer(i8), intent(in) :: step_number
    integer, intent(in) :: kept
    type(checkpoint_t) :: transaction
    call checkpoint_begin(transaction, step_number)
    call h5_write_array(transaction%file, 'component_a/step', step_number)
    call h5_write_slab(transaction%file, 'component_b/u', field, 2 * my_rank, [4, 3, 2 * n_ranks])
    call checkpoint_commit(transaction, kept)
  end subroutine write_checkpoint

  !> 'flip': change one byte of the first stored value of rank 0's field (1/7: a finite, wrong value
  !> without a checksum); 'header': change a letter of the group name component_b; 'truncate': keep
  !> the first half; 'zero': the same size in zero bytes.
  subroutine damage(path, how)
    character(len=*), intent(in) :: path, how
    integer(int8), allocatable :: bytes(:), pattern(:)
    integer :: unit, n, i
    open(newunit=unit, file=path, access='stream', form='unformatted', status='old', action='read')
    inquire(unit=unit, size=n)
    allocate(bytes(n))
    read(unit) bytes
    close(unit)
    select case (how)
    case ('flip')
      pattern = transfer(1.0_wp / 7.0_wp, [0_int8])
      do i = 1, n - size(pattern) + 1
        if (all(bytes(i:i + size(pattern) - 1) == pattern)) exit
      end do
      call check(i <= n - size(pattern) + 1, 'damage_flip_found_the_value')
      bytes(i) = not(bytes(i))
    case ('header')
      pattern = transfer('component_b', [0_int8])
      do i = 1, n - size(pattern) + 1
        if (all(bytes(i:i + size(pattern) - 1) == pattern)) exit
      end do
      call check(i <= n - size(pattern) + 1, 'damage_header_found_the_name')
      bytes(i + 1) = bytes(i + 1) + 1_int8   ! 'component_b' -> 'cpmponent_b'
    case ('truncate')
      bytes = bytes(1:n / 2)
    case ('zero')
      bytes = 0_int8
    end select
    open(newunit=unit, file=path, access='stream', form='unformatted', status='replace', action='write')
    write(unit) bytes
    close(unit)
  end subroutine damage

  subroutine copy_file(from, to)
    character(len=*), intent(in) :: from, to
    integer(int8), allocatable :: bytes(:)
    integer :: unit, n
    open(newunit=unit, file=from, access='stream', form='unformatted', status='old', action='read')
    inquire(unit=unit, size=n)
    allocate(bytes(n))
    read(unit) bytes
    close(unit)
    open(newunit=unit, file=to, access='stream', form='unformatted', status='replace', action='write')
    write(unit) bytes
    close(unit)
  end subroutine copy_file

  subroutine write_text(path)
    character(len=*), intent(in) :: path
    integer :: unit
    open(newunit=unit, file=path, status='replace', action='write')
    write(unit, '(a)') 'not a checkpoint'
    close(unit)
  end subroutine write_text
end program test_checkpoint_files
