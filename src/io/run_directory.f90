!> The run directory: created if needed, checked writable, never silently reused, and a record of
!> every file Agglo writes into it.
!>
!> A directory that already holds a run (its run.nml) is refused unless the deck says
!> &run restart = .true. (continue it) or &run overwrite = .true. (replace it).
!>
!> The manifest (agglo_manifest.txt, one path relative to the run directory per line) lists every
!> file and directory Agglo has created there: run_file registers each name before the file is
!> written, and the manifest is rewritten through a temporary name and rename() at each new name,
!> so it is always complete. overwrite deletes exactly the files of the manifest (and their .tmp
!> companions): a user's own files in the directory are never touched. A directory written before
!> manifests existed is cleaned by the exact names Agglo writes (docs/outputs.md).
!>
!> On restart, run.nml is rewritten only once the run has been restored from its checkpoint
!> (confirm_run_deck): a refused restart leaves the earlier run.nml as it was.
module run_directory
  use agglo_config, only: agglo_config_t, write_config
  use error_handling, only: fatal, input_error, input_error_text
  use text_format, only: int_text
  use parallel_env, only: is_root, barrier, root_text
  use file_system, only: rename_file, file_exists, make_directory, remove_path, longest_path
  use directory_listing, only: list_directory, name_length
  implicit none
  private
  public :: prepare_run_directory, run_directory_path, run_file, record_run_file, confirm_run_deck, forget_run_file, &
            manifest_name, checkpoint_subdirectory

  character(len=*), parameter :: manifest_name = 'agglo_manifest.txt'
  character(len=*), parameter :: checkpoint_subdirectory = 'checkpoints'
  !> The longest name Agglo writes inside the run directory.
  character(len=*), parameter :: longest_name = '/checkpoints/checkpoint_0000000000.h5.tmp'

  character(len=:), allocatable :: directory
  character(len=name_length), allocatable :: recorded(:)   !< the manifest (rank 0)
  integer :: n_recorded = 0
  type(agglo_config_t), allocatable :: pending_deck          !< run.nml still to write (restart)

contains

  !> The directory of this run ('' until prepare_run_directory is called).
  function run_directory_path() result(path)
    character(len=:), allocatable :: path
    path = ''
    if (allocated(directory)) path = directory
  end function run_directory_path

  !> Path of a file (or subdirectory) that Agglo writes inside the run directory; the name is
  !> recorded in the manifest (rank 0) the first time it is asked for.
  function run_file(name) result(path)
    character(len=*), intent(in) :: name
    character(len=:), allocatable :: path
    path = run_directory_path()//'/'//trim(name)
    if (allocated(directory) .and. is_root()) call record(trim(name))
  end function run_file

  !> Record name (relative to the run directory) in the manifest, before the file is written (rank 0).
  subroutine record_run_file(name)
    character(len=*), intent(in) :: name
    if (allocated(directory) .and. is_root()) call record(trim(name))
  end subroutine record_run_file

  !> Remove name from the manifest (rank 0; the caller has deleted the file).
  subroutine forget_run_file(name)
    character(len=*), intent(in) :: name
    integer :: i
    if (.not. is_root() .or. .not. allocated(recorded)) return
    do i = 1, n_recorded
      if (recorded(i) /= name) cycle
      recorded(i:n_recorded - 1) = recorded(i + 1:n_recorded)
      n_recorded = n_recorded - 1
      call write_manifest()
      return
    end do
  end subroutine forget_run_file

  subroutine prepare_run_directory(cfg)
    type(agglo_config_t), intent(in) :: cfg
    logical :: has_run
    character(len=:), allocatable :: problem
    directory = trim(cfg%output%directory)
    if (len(directory) == 0) directory = 'output/'//trim(cfg%run%name)
    ! Every path Agglo writes must fit the system's limit: a directory too long for its longest
    ! file is refused before anything is written.
    if (len(directory) + len(longest_name) > longest_path) call input_error('output', 'directory', &
        ''''//directory(1:40)//'...'' ('//int_text(len(directory))//' characters)', 'a path of at most '// &
        int_text(longest_path - len(longest_name))//' characters (the longest file path written, <directory>'// &
        longest_name//', must stay within the system''s limit of '//int_text(longest_path)//' characters, PATH_MAX)')
    problem = ''
    if (is_root()) problem = directory_problem(cfg, has_run)
    problem = root_text(problem)
    if (len(problem) > 0) call fatal(problem)
    if (is_root()) then
      allocate(recorded(64))
      n_recorded = 0
      if (cfg%run%restart) then
        call read_manifest()
        pending_deck = cfg
      else
        if (has_run) call remove_earlier_run()
        call record('run.nml')
      end if
      call record('agglo.log')   ! opened next, by every run (the manifest is complete before it)
      if (.not. cfg%run%restart) call write_run_deck(cfg)
    end if
    call barrier()
  end subroutine prepare_run_directory

  !> The deck error of the run directory, or '' if it may be used (rank 0 alone looks at the file
  !> system; prepare_run_directory shares the verdict so that every rank stops on it together).
  function directory_problem(cfg, has_run) result(problem)
    type(agglo_config_t), intent(in) :: cfg
    logical, intent(out) :: has_run
    character(len=:), allocatable :: problem
    logical :: ok
    integer :: unit, ios
    character(len=:), allocatable :: reason
    problem = ''
    has_run = file_exists(directory//'/run.nml')
    if (cfg%run%restart) then
      if (.not. has_run) problem = input_error_text('run', 'restart', '.true.', &
          '.false. (no earlier run found in '//directory//' to continue)')
    else if (has_run .and. .not. cfg%run%overwrite) then
      problem = input_error_text('output', 'directory', ''''//directory//'''', &
          'a directory without an earlier run in it, or set &run overwrite = .true. to replace that run')
    end if
    if (len(problem) > 0) return
    call make_directory(directory, ok, reason)
    if (.not. ok) then
      problem = input_error_text('output', 'directory', ''''//directory//'''', &
          'a directory that can be created (mkdir: '//reason//')')
      return
    end if
    open(newunit=unit, file=directory//'/.agglo_write_probe', status='replace', action='write', iostat=ios)
    if (ios /= 0) then
      problem = input_error_text('output', 'directory', ''''//directory//'''', 'a writable directory')
      return
    end if
    close(unit, status='delete')
  end function directory_problem

  !> After a restart has restored the run: the resolved deck of this run segment goes to run.nml.
  !> Collective; nothing happens on a fresh run (run.nml was written by prepare_run_directory).
  subroutine confirm_run_deck()
    if (is_root() .and. allocated(pending_deck)) then
      call write_run_deck(pending_deck)
      deallocate(pending_deck)
    end if
    call barrier()
  end subroutine confirm_run_deck

  !> Add name to the manifest if it is new (rank 0), rewriting the manifest file.
  subroutine record(name)
    character(len=*), intent(in) :: name
    if (len(name) == 0 .or. .not. allocated(recorded)) return
    if (len(name) > name_length) call fatal('run_directory: file name longer than '// &
                                            int_text(name_length)//' characters: '//name, collective=.false.)
    if (any(recorded(1:n_recorded) == name)) return
    call append_recorded(name)
    call write_manifest()
  end subroutine record

  !> One more name in the in-memory list (grown by doubling).
  subroutine append_recorded(name)
    character(len=*), intent(in) :: name
    character(len=name_length), allocatable :: grown(:)
    if (n_recorded == size(recorded)) then
      allocate(grown(2 * size(recorded)))
      grown(1:n_recorded) = recorded(1:n_recorded)
      call move_alloc(grown, recorded)
    end if
    n_recorded = n_recorded + 1
    recorded(n_recorded) = name
  end subroutine append_recorded

  !> The manifest file, written to a temporary name and renamed (never a torn list).
  subroutine write_manifest()
    integer :: unit, i, ios
    logical :: ok
    open(newunit=unit, file=directory//'/'//manifest_name//'.tmp', status='replace', action='write', iostat=ios)
    if (ios /= 0) call fatal('run_directory: cannot write '//directory//'/'//manifest_name//'.tmp', collective=.false.)
    do i = 1, n_recorded
      write(unit, '(a)') trim(recorded(i))
    end do
    close(unit)
    call rename_file(directory//'/'//manifest_name//'.tmp', directory//'/'//manifest_name, ok)
    if (.not. ok) call fatal('run_directory: cannot rename '//directory//'/'//manifest_name//'.tmp', &
                             collective=.false.)
  end subroutine write_manifest

  !> Load the manifest of the run in the directory (rank 0); none (older run): start an empty one.
  subroutine read_manifest()
    integer :: unit, ios
    character(len=name_length) :: line
    n_recorded = 0
    open(newunit=unit, file=directory//'/'//manifest_name, status='old', action='read', iostat=ios)
    if (ios /= 0) return
    do
      read(unit, '(a)', iostat=ios) line
      if (ios /= 0) exit
      if (len_trim(line) == 0) cycle
      call append_recorded(line)
    end do
    close(unit)
  end subroutine read_manifest

  !> Replace an earlier run (rank 0): delete the files it wrote, as its manifest lists them (or, for a
  !> run older than manifests, the exact names Agglo writes), then the manifest itself; a listed
  !> directory goes only if it is empty afterwards. The list starts empty for the new run.
  subroutine remove_earlier_run()
    character(len=name_length), allocatable :: names(:)
    integer :: i, pass
    logical :: ok
    if (file_exists(directory//'/'//manifest_name)) then
      call read_manifest()
      names = recorded(1:n_recorded)
    else
      call agglo_names_in_directory(names)
    end if
    do pass = 1, 2   ! files first, then the (now empty) directories they were in
      do i = size(names), 1, -1
        ! Only names inside the run directory (an edited manifest cannot reach outside it).
        if (names(i)(1:1) == '/' .or. index(names(i), '..') > 0) cycle
        call remove_path(directory//'/'//trim(names(i))//'.tmp', ok)
        call remove_path(directory//'/'//trim(names(i)), ok)
      end do
    end do
    call remove_path(directory//'/'//manifest_name, ok)
    n_recorded = 0
  end subroutine remove_earlier_run

  !> The files in the directory (and its checkpoints/) named exactly as Agglo names its outputs.
  subroutine agglo_names_in_directory(found)
    character(len=name_length), allocatable, intent(out) :: found(:)
    character(len=*), parameter :: fixed(*) = [character(len=24) :: 'agglo.log', 'fields.xdmf', &
        'fluid_statistics.dat', 'particles.h5', 'summary.json', 'flow_statistics.h5', 'final_field.h5', 'run.nml']
    character(len=name_length), allocatable :: names(:)
    logical :: ok
    integer :: i
    allocate(found(0))
    call list_directory(directory, names, ok)
    do i = 1, size(names)
      if (any(fixed == names(i)) .or. is_numbered(names(i), 'fields_', '.h5')) &
        found = [character(len=name_length) :: found, names(i)]
    end do
    call list_directory(directory//'/'//checkpoint_subdirectory, names, ok)
    do i = 1, size(names)
      if (is_numbered(names(i), 'checkpoint_', '.h5')) &
        found = [character(len=name_length) :: found, checkpoint_subdirectory//'/'//names(i)]
    end do
    found = [character(len=name_length) :: found, checkpoint_subdirectory]
  end subroutine agglo_names_in_directory

  !> name = <prefix><10 digits><ending>, nothing else.
  logical function is_numbered(name, prefix, ending)
    character(len=*), intent(in) :: name, prefix, ending
    integer :: n
    n = len_trim(name)
    is_numbered = .false.
    if (n /= len(prefix) + 10 + len(ending)) return
    if (name(1:len(prefix)) /= prefix .or. name(n - len(ending) + 1:n) /= ending) return
    is_numbered = verify(name(len(prefix) + 1:len(prefix) + 10), '0123456789') == 0
  end function is_numbered

  !> run.nml: the fully resolved deck, written to a temporary name and renamed when complete.
  subroutine write_run_deck(cfg)
    type(agglo_config_t), intent(in) :: cfg
    integer :: unit
    logical :: ok
    call record('run.nml')
    open(newunit=unit, file=directory//'/run.nml.tmp', status='replace', action='write')
    write(unit, '(a)') '! Resolved deck of this run (every variable, defaults included).'
    write(unit, '(a)') '! Deck file: '//trim(cfg%deck_path)
    call write_config(unit, cfg)
    close(unit)
    call rename_file(directory//'/run.nml.tmp', directory//'/run.nml', ok)
    if (.not. ok) call fatal('cannot rename '//directory//'/run.nml.tmp', collective=.false.)
  end subroutine write_run_deck
end module run_directory
