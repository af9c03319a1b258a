!> Agglo's HDF5 files: one small API over the HDF5 1.10 Fortran library for every file Agglo writes
!> (field snapshots, checkpoints, particle time series). This module opens, creates and closes
!> files and handles their groups and links; hdf5_datasets writes and reads whole datasets and
!> z-slabs, hdf5_series the extendible time series, hdf5_checks verifies a whole file.
!>
!> Two kinds of open files:
!>  - parallel (default): opened by every rank of MPI_COMM_WORLD with the MPI-IO driver; every call
!>    on it is then COLLECTIVE (all ranks call it, in the same order, with the same names).
!>  - serial (h5_create / h5_open with serial = .true.): opened by the calling rank alone with the
!>    default (POSIX) driver; the calls then involve only that rank. Used by the rank-0 writers
!>    (particle time series) in an MPI run.
!>
!> Names may contain groups ("fluid/u", "forcing/state"); missing intermediate groups are created
!> on write. h5_create(..., complete_on_close = .true.) writes <path>.tmp and h5_close renames it to
!> <path> once every rank has written (checkpoints, snapshots, final fields): a killed run leaves at
!> most a .tmp file, never a torn file under the final name. h5_create(..., checksums = .true.)
!> makes every dataset chunked with HDF5's Fletcher-32 checksum filter (hdf5_datasets): a corrupted
!> chunk is then an error on reading, never wrong values.
!> A parallel file with a long path is handed to MPI-IO under a short name of it (below).
!> Call h5_finalize once before MPI_Finalize (the library is opened on first use).
module hdf5_files
  use, intrinsic :: iso_c_binding, only: c_int
  use hdf5, only: hid_t, hsize_t, h5open_f, h5close_f, h5pcreate_f, h5pclose_f, h5pset_fapl_mpio_f, &
                  h5pset_dxpl_mpio_f, h5pset_libver_bounds_f, H5F_LIBVER_V18_F, H5F_LIBVER_LATEST_F, &
                  H5P_FILE_ACCESS_F, H5P_DATASET_XFER_F, H5FD_MPIO_COLLECTIVE_F, h5fcreate_f, h5fopen_f, &
                  h5fclose_f, h5fflush_f, H5F_ACC_TRUNC_F, H5F_ACC_RDWR_F, H5F_ACC_RDONLY_F, H5F_SCOPE_GLOBAL_F, &
                  h5gcreate_f, h5gclose_f, h5lexists_f, h5ldelete_f, h5gn_members_f, h5gget_obj_info_idx_f, &
                  H5G_GROUP_F, H5G_DATASET_F
  use mpi_f08, only: MPI_COMM_WORLD, MPI_INFO_NULL
  use error_handling, only: fatal
  use file_system, only: file_exists, rename_file, short_name_t, open_short_name, close_short_name
  use parallel_env, only: my_rank, barrier, all_ranks
  implicit none
  private
  public :: h5_file_t, h5_create, h5_open, h5_close, h5_flush, h5_exists, h5_delete, h5_dataset_names, &
            h5_finalize, dataset_name_length
  ! For the other hdf5_* modules:
  public :: open_library, make_property_lists, require_ok, require_open, make_parent_groups

  !> Longest path handed to MPI-IO as it is. Open MPI 4.1.4's shared-file-pointer component
  !> 'lockedfile' probes every file it opens with a lock file named <path>.locktest.<rank>, built with
  !> sprintf into a 256-byte buffer: a 228-character path worked and 229 aborted (buffer overflow,
  !> SIGABRT) on 1 and 2 ranks. A longer path is opened through a short name of the same file
  !> (file_system, short_name_t); 220 leaves room for rank numbers up to 9 digits.
  integer, parameter :: longest_direct_path = 220

  !> Longest dataset name h5_dataset_names returns (with its groups).
  integer, parameter :: dataset_name_length = 256

  !> An open HDF5 file (parallel over MPI_COMM_WORLD, or serial on the calling rank).
  type :: h5_file_t
    integer(hid_t) :: id = -1_hid_t          !< HDF5 file identifier
    integer(hid_t) :: transfer = -1_hid_t    !< data-transfer property list (collective MPI-IO if parallel)
    logical :: is_open = .false.
    logical :: serial = .false.              !< opened by this rank alone with the default driver
    logical :: writable = .false.
    logical :: checksums = .false.           !< datasets chunked with the Fletcher-32 filter
    character(len=:), allocatable :: path
    character(len=:), allocatable :: complete_path   !< '' or the name path gets when the file is closed
    type(short_name_t) :: io_name            !< the name HDF5 and MPI-IO open (path, or a short name of it)
  end type h5_file_t

  !> The one piece of state of the HDF5 layer: whether this process has initialised the HDF5 Fortran
  !> library. h5open_f is not idempotent (each call copies the predefined types anew, and those
  !> copies are never released), and h5close_f must run once, before MPI_Finalize, for the MPI-IO
  !> driver to release its communicators: the library is a per-process resource, so this flag is too.
  logical :: library_open = .false.

contains

  !> Initialise the HDF5 library on first use.
  subroutine open_library()
    integer :: status
    if (library_open) return
    call h5open_f(status)
    if (status /= 0) call fatal('hdf5: the HDF5 library could not be initialised (h5open_f)', collective=.false.)
    library_open = .true.
  end subroutine open_library

  !> Close the HDF5 library (every file must be closed). Call before MPI_Finalize; safe to call twice.
  subroutine h5_finalize()
    integer :: status
    if (.not. library_open) return
    call h5close_f(status)
    library_open = .false.
  end subroutine h5_finalize

  !> Stop with the file (and object) named when an HDF5 call failed.
  subroutine require_ok(status, action, file, name)
    integer, intent(in) :: status
    character(len=*), intent(in) :: action
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in), optional :: name
    character(len=:), allocatable :: where
    if (status >= 0) return
    where = ''
    if (allocated(file%path)) where = file%path
    if (present(name)) where = where//':/'//trim(name)
    call fatal('hdf5: '//action//' failed for '//where, collective=.false.)
  end subroutine require_ok

  !> File-access and transfer property lists of a new parallel or serial file handle.
  subroutine make_property_lists(file, access)
    type(h5_file_t), intent(inout) :: file
    integer(hid_t), intent(out) :: access
    integer :: status
    call h5pcreate_f(H5P_FILE_ACCESS_F, access, status)
    call require_ok(status, 'h5pcreate (file access)', file)
    call h5pcreate_f(H5P_DATASET_XFER_F, file%transfer, status)
    call require_ok(status, 'h5pcreate (transfer)', file)
    if (.not. file%serial) then
      call h5pset_fapl_mpio_f(access, MPI_COMM_WORLD%MPI_VAL, MPI_INFO_NULL%MPI_VAL, status)
      call require_ok(status, 'h5pset_fapl_mpio', file)
      call h5pset_dxpl_mpio_f(file%transfer, H5FD_MPIO_COLLECTIVE_F, status)
      call require_ok(status, 'h5pset_dxpl_mpio', file)
    end if
  end subroutine make_property_lists

  !> Create (truncate) a file. Collective unless serial = .true. (then this rank alone).
  subroutine h5_create(file, path, serial, complete_on_close, checksums)
    type(h5_file_t), intent(out) :: file
    character(len=*), intent(in) :: path
    logical, intent(in), optional :: serial
    logical, intent(in), optional :: complete_on_close   !< write path.tmp; h5_close renames it to path
    logical, intent(in), optional :: checksums           !< Fletcher-32 on every dataset
    integer(hid_t) :: access
    integer :: status
    call open_library()
    file%path = trim(path)
    file%complete_path = ''
    if (present(complete_on_close)) then
      if (complete_on_close) then
        file%complete_path = trim(path)
        file%path = trim(path)//'.tmp'
      end if
    end if
    file%serial = .false.
    if (present(serial)) file%serial = serial
    if (present(checksums)) file%checksums = checksums
    call choose_io_name(file)
    call make_property_lists(file, access)
    if (file%checksums) then
      ! The 1.8 file format and later checksum the file's metadata too (superblock v2, object
      ! headers v2, B-tree v2 nodes), so a damaged header is caught like damaged data.
      call h5pset_libver_bounds_f(access, H5F_LIBVER_V18_F, H5F_LIBVER_LATEST_F, status)
      call require_ok(status, 'h5pset_libver_bounds', file)
    end if
    call h5fcreate_f(file%io_name%path, H5F_ACC_TRUNC_F, file%id, status, access_prp=access)
    call require_ok(status, 'creating the file', file)
    call h5pclose_f(access, status)
    file%is_open = .true.
    file%writable = .true.
  end subroutine h5_create

  !> Open an existing file (read-only unless writable). Collective unless serial = .true.
  subroutine h5_open(file, path, writable, serial)
    type(h5_file_t), intent(out) :: file
    character(len=*), intent(in) :: path
    logical, intent(in) :: writable
    logical, intent(in), optional :: serial
    integer(hid_t) :: access
    integer :: status
    logical :: found
    call open_library()
    file%path = trim(path)
    file%serial = .false.
    if (present(serial)) file%serial = serial
    if (file%serial) then
      found = file_exists(file%path)
    else   ! each rank looks for itself (another node may not see the file): all stop together
      found = all_ranks(file_exists(file%path))
    end if
    if (.not. found) call fatal('hdf5: cannot open '//file%path//': no such file', collective=.not. file%serial)
    call choose_io_name(file)
    call make_property_lists(file, access)
    if (writable) then
      call h5fopen_f(file%io_name%path, H5F_ACC_RDWR_F, file%id, status, access_prp=access)
    else
      call h5fopen_f(file%io_name%path, H5F_ACC_RDONLY_F, file%id, status, access_prp=access)
    end if
    ! A parallel open that failed anywhere stops every rank: with a clean exit where it failed on all
    ! of them (e.g. an init_file that is not an HDF5 file); a rank holding the file open aborts instead.
    if (.not. file%serial) then
      if (.not. all_ranks(status >= 0)) call fatal('hdf5: cannot open '//file%path// &
          ' (not an HDF5 file, or not writable?)', collective=(status < 0))
    end if
    call require_ok(status, 'opening the file (not an HDF5 file, or not writable?)', file)
    call h5pclose_f(access, status)
    file%is_open = .true.
    file%writable = writable
  end subroutine h5_open

  !> The name the file is opened under: its path, or for a parallel file with a path longer than
  !> longest_direct_path a short name of it. The file's own name (after the last '/') must then fit.
  subroutine choose_io_name(file)
    type(h5_file_t), intent(inout) :: file
    character(len=16) :: text
    if (file%serial .or. len(file%path) <= longest_direct_path) then
      file%io_name%path = file%path
      return
    end if
    call open_short_name(file%path, file%io_name)
    if (len(file%io_name%path) <= longest_direct_path) return
    call close_short_name(file%io_name)
    write(text, '(i0)') longest_direct_path
    call fatal('hdf5: cannot open '//file%path//' through MPI-IO: Open MPI 4.1 aborts on names longer than '// &
               trim(text)//' characters, and no short name of it fits (/proc/self/fd/<n>/<file name>: Linux, '// &
               'a file name after the last / of at most about 195 characters)', collective=.false.)
  end subroutine choose_io_name

  subroutine h5_close(file)
    type(h5_file_t), intent(inout) :: file
    integer :: status
    logical :: renamed
    if (.not. file%is_open) return
    call h5pclose_f(file%transfer, status)
    call h5fclose_f(file%id, status)
    call require_ok(status, 'closing the file', file)
    call close_short_name(file%io_name)
    file%is_open = .false.
    file%id = -1_hid_t
    file%transfer = -1_hid_t
    if (.not. allocated(file%complete_path)) return
    if (len(file%complete_path) == 0) return
    ! Complete only now: a run killed before this point leaves the .tmp name, never a torn file
    ! under the final name (rename() is atomic on one file system).
    if (.not. file%serial) call barrier()   ! every rank's data are in the file
    if (file%serial .or. my_rank == 0) then
      call rename_file(file%path, file%complete_path, renamed)
      if (.not. renamed) call fatal('hdf5: cannot rename '//file%path//' to '//file%complete_path, collective=.false.)
    end if
    if (.not. file%serial) call barrier()   ! nobody reads the final name before it exists
    file%path = file%complete_path
    file%complete_path = ''
  end subroutine h5_close

  !> Push buffered data to the file system (the file stays open).
  subroutine h5_flush(file)
    type(h5_file_t), intent(in) :: file
    integer :: status
    call h5fflush_f(file%id, H5F_SCOPE_GLOBAL_F, status)
    call require_ok(status, 'flushing the file', file)
  end subroutine h5_flush

  !> Stop unless the file is open (and writable, for_writing).
  subroutine require_open(file, name, for_writing)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    logical, intent(in) :: for_writing
    if (.not. file%is_open) call fatal('hdf5: access to '//trim(name)//' in a file that is not open', &
                                       collective=.false.)
    if (for_writing .and. .not. file%writable) &
      call fatal('hdf5: writing '//trim(name)//' to '//file%path//', opened read-only', collective=.false.)
  end subroutine require_open

  ! ---------------------------------------------------------------------------------------------
  ! Groups and links
  ! ---------------------------------------------------------------------------------------------

  !> Does the object (group or dataset, path with groups allowed) exist?
  logical function h5_exists(file, name)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer :: cut, status
    character(len=:), allocatable :: clean
    logical :: found
    call require_open(file, name, .false.)
    clean = strip_slashes(name)
    h5_exists = .false.
    if (len(clean) == 0) then
      h5_exists = .true.
      return
    end if
    ! h5lexists_f fails (rather than answers no) when an intermediate group is missing: walk the path.
    cut = 0
    do
      cut = next_slash(clean, cut)
      call h5lexists_f(file%id, clean(1:cut - 1), found, status)
      if (status < 0 .or. .not. found) return
      if (cut > len(clean)) exit
    end do
    h5_exists = .true.
  end function h5_exists

  !> Position of the next '/' after position after (len + 1 when none).
  integer function next_slash(text, after)
    character(len=*), intent(in) :: text
    integer, intent(in) :: after
    integer :: offset
    offset = index(text(after + 1:), '/')
    if (offset == 0) then
      next_slash = len(text) + 1
    else
      next_slash = after + offset
    end if
  end function next_slash

  function strip_slashes(name) result(clean)
    character(len=*), intent(in) :: name
    character(len=:), allocatable :: clean
    integer :: first, last
    first = 1
    last = len_trim(name)
    do while (first <= last)
      if (name(first:first) /= '/') exit
      first = first + 1
    end do
    do while (last >= first)
      if (name(last:last) /= '/') exit
      last = last - 1
    end do
    clean = name(first:last)
  end function strip_slashes

  !> Create the groups on the path of name (everything before its last '/') that do not exist yet.
  subroutine make_parent_groups(file, name)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer :: cut, status
    integer(hid_t) :: group
    logical :: found
    cut = 0
    do
      cut = next_slash(name, cut)
      if (cut > len(name)) exit
      call h5lexists_f(file%id, name(1:cut - 1), found, status)
      call require_ok(status, 'looking up a group', file, name(1:cut - 1))
      if (.not. found) then
        call h5gcreate_f(file%id, name(1:cut - 1), group, status)
        call require_ok(status, 'creating a group', file, name(1:cut - 1))
        call h5gclose_f(group, status)
      end if
    end do
  end subroutine make_parent_groups

  !> Remove the dataset or group name (with its members) if it exists; nothing happens if it does
  !> not. Collective on a parallel file. (HDF5 does not return the freed space to the file system.)
  subroutine h5_delete(file, name)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer :: status
    call require_open(file, name, .true.)
    if (.not. h5_exists(file, name)) return
    call h5ldelete_f(file%id, name, status)
    call require_ok(status, 'deleting a link', file, name)
  end subroutine h5_delete

  !> Names of every dataset in the file, below every group (as 'group/dataset', no leading slash), in
  !> HDF5's index order. A restarted run uses it to shrink the time series of a file it continues.
  subroutine h5_dataset_names(file, names)
    type(h5_file_t), intent(in) :: file
    character(len=dataset_name_length), allocatable, intent(out) :: names(:)
    call require_open(file, '/', .false.)
    allocate(names(0))
    call collect_datasets(file, '', names)
  end subroutine h5_dataset_names

  recursive subroutine collect_datasets(file, group, names)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group            !< '' (the root) or 'a/b/'
    character(len=dataset_name_length), allocatable, intent(inout) :: names(:)
    character(len=dataset_name_length) :: member
    integer :: members, i, kind, status
    call h5gn_members_f(file%id, '/'//group, members, status)
    call require_ok(status, 'listing a group', file, '/'//group)
    do i = 0, members - 1
      call h5gget_obj_info_idx_f(file%id, '/'//group, i, member, kind, status)
      call require_ok(status, 'reading the entries of a group', file, '/'//group)
      if (len(group) + len_trim(member) > dataset_name_length) call fatal('hdf5: a name in '//file%path// &
          ' is longer than the listing allows: '//group//trim(member), collective=.false.)
      if (kind == H5G_GROUP_F) then
        call collect_datasets(file, group//trim(member)//'/', names)
      else if (kind == H5G_DATASET_F) then
        names = [character(len=dataset_name_length) :: names, group//trim(member)]
      end if
    end do
  end subroutine collect_datasets
end module hdf5_files
