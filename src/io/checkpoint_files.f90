!> Checkpoint files: where they live, how they are made safe against a killed run, which one a
!> restart continues from.
!>
!> A checkpoint of step n is written to <run dir>/checkpoints/checkpoint_<n, 10 digits>.h5.tmp and
!> renamed to .../checkpoint_<n>.h5 only after the file is complete and closed (rename() is atomic
!> on one file system). A run killed while writing leaves at most a .tmp file, which
!> newest_checkpoint never returns; so every *.h5 in the directory is a complete checkpoint.
!> What goes into the file (fields, multistep history, step, time, dt, random streams) is written
!> by the modules that hold that state, with the hdf5_io routines between checkpoint_begin and
!> checkpoint_commit.
!>
!> Every routine here is collective (all ranks call it).
module checkpoint_files
  use mpi_f08, only: MPI_Bcast, MPI_INTEGER, MPI_CHARACTER, MPI_COMM_WORLD
  use agglo_kinds, only: i8
  use error_handling, only: fatal
  use file_system, only: rename_file, make_directory, delete_file
  use parallel_env, only: is_root, barrier
  use run_directory, only: run_directory_path
  use directory_listing, only: list_directory, name_length
  use hdf5_io, only: h5_file_t, h5_create, h5_close
  implicit none
  private
  public :: checkpoint_begin, checkpoint_commit, newest_checkpoint, checkpoint_directory, checkpoint_path

  character(len=*), parameter :: prefix = 'checkpoint_', suffix = '.h5', temporary_suffix = '.h5.tmp'
  integer, parameter :: step_digits = 10

  !> Start the checkpoint of step (integer or integer(i8)): creates the .h5.tmp file.
  interface checkpoint_begin
    module procedure checkpoint_begin_i8, checkpoint_begin_int
  end interface checkpoint_begin

  !> Close the checkpoint of step, rename it complete, prune the oldest beyond checkpoints_kept.
  interface checkpoint_commit
    module procedure checkpoint_commit_i8, checkpoint_commit_int
  end interface checkpoint_commit

contains

  !> <run dir>/checkpoints
  function checkpoint_directory() result(path)
    character(len=:), allocatable :: path
    if (len(run_directory_path()) == 0) &
      call fatal('checkpoint_files: the run directory is not set up (prepare_run_directory first)')
    path = run_directory_path()//'/checkpoints'
  end function checkpoint_directory

  !> Path of the complete checkpoint of step (the .tmp name when temporary = .true.).
  function checkpoint_path(step, temporary) result(path)
    integer(i8), intent(in) :: step
    logical, intent(in), optional :: temporary
    character(len=:), allocatable :: path
    character(len=step_digits) :: digits
    if (step < 0_i8 .or. step >= 10_i8**step_digits) &
      call fatal('checkpoint_files: step outside 0 .. 9999999999 cannot name a checkpoint')
    write(digits, '(i10.10)') step
    path = checkpoint_directory()//'/'//prefix//digits//suffix
    if (present(temporary)) then
      if (temporary) path = path//'.tmp'
    end if
  end function checkpoint_path

  subroutine checkpoint_begin_i8(step, file)
    integer(i8), intent(in) :: step
    type(h5_file_t), intent(out) :: file
    logical :: ok
    if (is_root()) then
      call make_directory(checkpoint_directory(), ok)
      if (.not. ok) call fatal('checkpoint_files: cannot create '//checkpoint_directory(), collective=.false.)
    end if
    call barrier()
    call h5_create(file, checkpoint_path(step), complete_on_close=.true.)
  end subroutine checkpoint_begin_i8

  subroutine checkpoint_begin_int(step, file)
    integer, intent(in) :: step
    type(h5_file_t), intent(out) :: file
    call checkpoint_begin_i8(int(step, i8), file)
  end subroutine checkpoint_begin_int

  subroutine checkpoint_commit_i8(file, step, checkpoints_kept)
    type(h5_file_t), intent(inout) :: file
    integer(i8), intent(in) :: step
    integer, intent(in) :: checkpoints_kept     !< &output checkpoints_kept (>= 1)
    if (checkpoints_kept < 1) call fatal('checkpoint_files: checkpoints_kept must be >= 1')
    call h5_close(file)   ! renames the .tmp file to its final name once every rank has written
    if (is_root()) call prune(step, checkpoints_kept)
    call barrier()
  end subroutine checkpoint_commit_i8

  subroutine checkpoint_commit_int(file, step, checkpoints_kept)
    type(h5_file_t), intent(inout) :: file
    integer, intent(in) :: step, checkpoints_kept
    call checkpoint_commit_i8(file, int(step, i8), checkpoints_kept)
  end subroutine checkpoint_commit_int

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

  !> Delete the complete checkpoints older than the newest kept ones, and the .tmp files other
  !> than that of the step just committed (left behind by killed runs). Rank 0 only.
  subroutine prune(step, checkpoints_kept)
    integer(i8), intent(in) :: step
    integer, intent(in) :: checkpoints_kept
    integer(i8), allocatable :: steps(:)
    integer :: i, newer
    call checkpoint_steps(.false., steps)
    do i = 1, size(steps)
      newer = count(steps > steps(i))
      if (newer >= checkpoints_kept) call delete_file(checkpoint_path(steps(i)))
    end do
    call checkpoint_steps(.true., steps)
    do i = 1, size(steps)
      if (steps(i) /= step) call delete_file(checkpoint_path(steps(i), temporary=.true.))
    end do
  end subroutine prune

  !> Path of the newest complete checkpoint of this run ('' if there is none). Collective: rank 0
  !> looks and every rank gets its answer.
  function newest_checkpoint() result(path)
    character(len=:), allocatable :: path
    integer(i8), allocatable :: steps(:)
    character(len=1024) :: shared
    integer :: length
    shared = ''
    if (is_root()) then
      call checkpoint_steps(.false., steps)
      if (size(steps) > 0) shared = checkpoint_path(maxval(steps))
    end if
    length = len_trim(shared)
    call MPI_Bcast(length, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
    call MPI_Bcast(shared, len(shared), MPI_CHARACTER, 0, MPI_COMM_WORLD)
    path = shared(1:length)
  end function newest_checkpoint
end module checkpoint_files
