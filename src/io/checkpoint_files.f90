!> Checkpoints as transactions: the driver opens one, every component that holds state (the fluid,
!> the forcing, later the particle system) writes its own group through the open file, and one
!> commit makes the checkpoint complete. Reading mirrors it: the driver opens the newest valid
!> checkpoint, each component reads its group, the driver closes it. This module knows no
!> component: a new one adds its group without a change here.
!>
!>   call checkpoint_begin(checkpoint, step)           ! writing
!>   call <component>_write_checkpoint(checkpoint%file, ...)   ! group '<component>/...'
!>   call checkpoint_commit(checkpoint, checkpoints_kept)
!>
!>   call checkpoint_open_newest(checkpoint)            ! reading (restart)
!>   call <component>_read_checkpoint(checkpoint%file, ...)
!>   call checkpoint_close(checkpoint)
!>
!> A checkpoint of step n is written to <run dir>/checkpoints/checkpoint_<n, 10 digits>.h5.tmp and
!> renamed to .../checkpoint_<n>.h5 only after the file is complete and closed (rename() is atomic on
!> one file system): a run killed while writing leaves at most a .tmp file, which is never read.
!> Every dataset carries a Fletcher-32 checksum (hdf5_files, checksums = .true.), and the commit writes
!> checkpoint/step (the step, as in the name) and last checkpoint/complete = 1. On restart the
!> newest file is verified (it opens, every dataset reads back with its checksum, its stored step
!> is the one in its name and it is marked complete); a damaged one (truncated, zeroed, corrupted)
!> or one merely named like a checkpoint is passed over with a warning naming it, and the next
!> older one is tried.
!>
!> Every routine here is collective (all ranks call it).
module checkpoint_files
  use agglo_kinds, only: i8
  use error_handling, only: fatal
  use logger, only: log_line
  use file_system, only: make_directory, delete_file
  use parallel_env, only: is_root, barrier, root_text
  use run_directory, only: run_directory_path, run_file, confirm_run_deck, forget_run_file, checkpoint_subdirectory
  use directory_listing, only: list_directory, name_length
  use field_output, only: discard_snapshots_after
  use hdf5_files, only: h5_file_t, h5_create, h5_open, h5_close, h5_exists
  use hdf5_datasets, only: h5_read_scalar, h5_write_array, h5_read_array
  use hdf5_checks, only: h5_verify
  implicit none
  private
  public :: checkpoint_t, checkpoint_begin, checkpoint_commit, checkpoint_open_newest, checkpoint_open, &
            checkpoint_close, checkpoint_directory, checkpoint_path, checkpoint_is_valid, newest_checkpoint

  !> An open checkpoint (being written, or read on restart).
  type :: checkpoint_t
    type(h5_file_t) :: file            !< components write and read their groups through it
    integer(i8) :: step = -1_i8        !< the step the checkpoint holds
    character(len=:), allocatable :: path
  end type checkpoint_t

  character(len=*), parameter :: prefix = 'checkpoint_', suffix = '.h5', temporary_suffix = '.h5.tmp'
  integer, parameter :: step_digits = 10

  !> Start the checkpoint of step (integer or integer(i8)): creates the .h5.tmp file.
  interface checkpoint_begin
    module procedure checkpoint_begin_i8, checkpoint_begin_int
  end interface checkpoint_begin

contains

  !> <run dir>/checkpoints
  function checkpoint_directory() result(path)
    character(len=:), allocatable :: path
    if (len(run_directory_path()) == 0) &
      call fatal('checkpoint_files: the run directory is not set up (prepare_run_directory first)', &
                 collective=.false.)   ! also reached from rank 0 alone (prune, newest_checkpoint)
    path = run_directory_path()//'/'//checkpoint_subdirectory
  end function checkpoint_directory

  !> checkpoints/checkpoint_<step>.h5, relative to the run directory.
  function checkpoint_name(step) result(name)
    integer(i8), intent(in) :: step
    character(len=:), allocatable :: name
    character(len=step_digits) :: digits
    if (step < 0_i8 .or. step >= 10_i8**step_digits) &
      call fatal('checkpoint_files: step outside 0 .. 9999999999 cannot name a checkpoint', &
                 collective=.false.)   ! also reached from rank 0 alone (prune)
    write(digits, '(i10.10)') step
    name = checkpoint_subdirectory//'/'//prefix//digits//suffix
  end function checkpoint_name

  !> Path of the complete checkpoint of step (the .tmp name when temporary = .true.).
  function checkpoint_path(step, temporary) result(path)
    integer(i8), intent(in) :: step
    logical, intent(in), optional :: temporary
    character(len=:), allocatable :: path
    path = run_directory_path()//'/'//checkpoint_name(step)
    if (present(temporary)) then
      if (temporary) path = path//'.tmp'
    end if
  end function checkpoint_path

  subroutine checkpoint_begin_i8(checkpoint, step)
    type(checkpoint_t), intent(out) :: checkpoint
    integer(i8), intent(in) :: step
    logical :: ok
    character(len=:), allocatable :: reason
    if (is_root()) then
      call make_directory(run_file(checkpoint_subdirectory), ok, reason)
      if (.not. ok) call fatal('checkpoint_files: cannot create '//checkpoint_directory()//': '//reason, &
                               collective=.false.)
    end if
    call barrier()
    checkpoint%step = step
    checkpoint%path = run_file(checkpoint_name(step))   ! recorded in the run's manifest
    call h5_create(checkpoint%file, checkpoint%path, complete_on_close=.true., checksums=.true.)
  end subroutine checkpoint_begin_i8

  subroutine checkpoint_begin_int(checkpoint, step)
    type(checkpoint_t), intent(out) :: checkpoint
    integer, intent(in) :: step
    call checkpoint_begin_i8(checkpoint, int(step, i8))
  end subroutine checkpoint_begin_int

  !> Mark the checkpoint complete, close it (renamed to its final name once every rank has written)
  !> and delete the oldest beyond checkpoints_kept.
  subroutine checkpoint_commit(checkpoint, checkpoints_kept)
    type(checkpoint_t), intent(inout) :: checkpoint
    integer, intent(in) :: checkpoints_kept     !< &output checkpoints_kept (>= 1)
    if (checkpoints_kept < 1) call fatal('checkpoint_files: checkpoints_kept must be >= 1')
    call h5_write_array(checkpoint%file, 'checkpoint/step', checkpoint%step)
    call h5_write_array(checkpoint%file, 'checkpoint/complete', 1)
    call h5_close(checkpoint%file)
    if (is_root()) call prune(checkpoint%step, checkpoints_kept)
    call barrier()
  end subroutine checkpoint_commit

  !> Restart: open the newest valid checkpoint of this run for reading (warnings name the files passed
  !> over). Stops with a message when there is none.
  subroutine checkpoint_open_newest(checkpoint)
    type(checkpoint_t), intent(out) :: checkpoint
    character(len=:), allocatable :: path
    path = newest_checkpoint()
    if (len(path) == 0) call fatal('deck: &run restart = .true. but the run directory '//checkpoint_directory()// &
                                   ' holds no complete and valid checkpoint to continue from')
    call checkpoint_open(checkpoint, path)
  end subroutine checkpoint_open_newest

  !> Open the checkpoint at path for reading (collective, parallel).
  subroutine checkpoint_open(checkpoint, path)
    type(checkpoint_t), intent(out) :: checkpoint
    character(len=*), intent(in) :: path
    checkpoint%path = path
    call h5_open(checkpoint%file, path, writable=.false.)
    call h5_read_scalar(checkpoint%file, 'checkpoint/step', checkpoint%step)
  end subroutine checkpoint_open

  !> End of a restart: every component has read its group. The field snapshots of later steps (an
  !> interrupted or stopped history) leave the run, and the deck of the continued run goes to run.nml
  !> (a refused restart leaves both as they were). Collective.
  subroutine checkpoint_close(checkpoint)
    type(checkpoint_t), intent(inout) :: checkpoint
    call h5_close(checkpoint%file)
    call discard_snapshots_after(checkpoint%step)
    call confirm_run_deck()
  end subroutine checkpoint_close

  !> Steps of the checkpoint files in the directory: complete ones, or .tmp ones when temporary.
  subroutine checkpoint_steps(temporary, steps)
    logical, intent(in) :: temporary
    integer(i8), allocatable, intent(out) :: steps(:)
    character(len=name_length), allocatable :: names(:)
    character(len=:), allocatable :: ending
    integer(i8) :: step
    integer :: i, ios, n
    logical :: ok
    allocate(steps(0))
    call list_directory(checkpoint_directory(), names, ok)
    if (.not. ok) return
    ending = suffix
    if (temporary) ending = temporary_suffix
    deallocate(steps)
    allocate(steps(size(names)))
    n = 0
    do i = 1, size(names)
      ! checkpoint_<10 digits><ending>, nothing else (a foreign or half-named file is ignored).
      if (len_trim(names(i)) /= len(prefix) + step_digits + len(ending)) cycle
      if (names(i)(1:len(prefix)) /= prefix) cycle
      if (names(i)(len(prefix) + step_digits + 1:len_trim(names(i))) /= ending) cycle
      if (verify(names(i)(len(prefix) + 1:len(prefix) + step_digits), '0123456789') /= 0) cycle
      read(names(i)(len(prefix) + 1:len(prefix) + step_digits), '(i10)', iostat=ios) step
      if (ios /= 0) cycle
      n = n + 1
      steps(n) = step
    end do
    steps = steps(1:n)
  end subroutine checkpoint_steps

  !> Delete the complete checkpoints older than the step just committed beyond the newest kept ones
  !> (counting that step), and the .tmp files other than that of the step just committed (left
  !> behind by killed runs). Files named for later steps (an abandoned history, or not Agglo's) are
  !> not counted and not touched. Rank 0 only.
  subroutine prune(step, checkpoints_kept)
    integer(i8), intent(in) :: step
    integer, intent(in) :: checkpoints_kept
    integer(i8), allocatable :: steps(:)
    integer :: i, newer
    call checkpoint_steps(.false., steps)
    do i = 1, size(steps)
      if (steps(i) >= step) cycle
      newer = count(steps > steps(i) .and. steps <= step)
      if (newer >= checkpoints_kept) then
        call delete_file(checkpoint_path(steps(i)))
        call forget_run_file(checkpoint_name(steps(i)))
      end if
    end do
    call checkpoint_steps(.true., steps)
    do i = 1, size(steps)
      if (steps(i) /= step) call delete_file(checkpoint_path(steps(i), temporary=.true.))
    end do
  end subroutine prune

  !> Is the file at path a valid checkpoint of step? (rank 0 alone; reason says why not)
  subroutine checkpoint_is_valid(path, step, ok, reason)
    character(len=*), intent(in) :: path
    integer(i8), intent(in) :: step
    logical, intent(out) :: ok
    character(len=:), allocatable, intent(out) :: reason
    type(h5_file_t) :: file
    integer(i8) :: stored_step
    integer :: complete
    character(len=24) :: text
    call h5_verify(path, ok, reason)   ! opens, and every dataset reads back with its checksum
    if (.not. ok) return
    call h5_open(file, path, writable=.false., serial=.true.)
    ok = h5_exists(file, 'checkpoint/step') .and. h5_exists(file, 'checkpoint/complete')
    if (.not. ok) then
      reason = 'not marked complete (no checkpoint/step and checkpoint/complete)'
    else
      call h5_read_scalar(file, 'checkpoint/step', stored_step)
      call h5_read_scalar(file, 'checkpoint/complete', complete)
      write(text, '(i0)') stored_step
      if (stored_step /= step) then
        ok = .false.
        reason = 'it holds step '//trim(text)//', not the step in its name'
      else if (complete /= 1) then
        ok = .false.
        reason = 'not marked complete'
      end if
    end if
    call h5_close(file)
  end subroutine checkpoint_is_valid

  !> Path of the newest valid checkpoint of this run ('' if there is none). Collective: rank 0
  !> checks, newest first, and every rank gets its answer; each file passed over is named in a warning.
  function newest_checkpoint() result(path)
    character(len=:), allocatable :: path
    character(len=:), allocatable :: reason
    integer(i8), allocatable :: steps(:)
    character(len=:), allocatable :: found
    integer :: newest
    logical :: ok
    found = ''
    if (is_root()) then
      call checkpoint_steps(.false., steps)
      do while (size(steps) > 0)
        newest = maxloc(steps, 1)
        call checkpoint_is_valid(checkpoint_path(steps(newest)), steps(newest), ok, reason)
        if (ok) then
          found = checkpoint_path(steps(newest))
          exit
        end if
        call log_line('agglo: warning: checkpoint '//checkpoint_path(steps(newest))//' is not usable ('// &
                      reason//'); trying the previous one')
        steps = [steps(:newest - 1), steps(newest + 1:)]
      end do
    end if
    path = root_text(found)
  end function newest_checkpoint
end module checkpoint_files
