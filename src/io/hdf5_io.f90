!> Agglo's HDF5 toolkit: one small API over the HDF5 1.10 Fortran library for every file Agglo
!> writes (field snapshots, checkpoints, particle time series).
!>
!> Two kinds of open files:
!>  - parallel (default): opened by every rank of MPI_COMM_WORLD with the MPI-IO driver; every call
!>    below is then COLLECTIVE (all ranks call it, in the same order, with the same names).
!>    Raw data move with collective MPI-IO transfers. For h5_write_array / h5_append the values of
!>    rank 0 are written (the other ranks take part with an empty selection); h5_read_array gives
!>    every rank the values.
!>  - serial (h5_create / h5_open with serial = .true.): opened by the calling rank alone with the
!>    default (POSIX) driver; the calls then involve only that rank. Used by the rank-0 writers
!>    (particle time series) in an MPI run.
!>
!> Names may contain groups ("fluid/u", "forcing/state"); missing intermediate groups are created
!> on write. Array shapes are given in Fortran order: h5dump and h5py show them reversed
!> (a Fortran (nx, ny, nz) dataset is (nz, ny, nx) in h5py).
!> h5_create(..., complete_on_close = .true.) writes <path>.tmp and h5_close renames it to <path>
!> once every rank has written (checkpoints, snapshots, final fields): a killed run leaves at most
!> a .tmp file, never a torn file under the final name.
!> h5_create(..., checksums = .true.) stores every dataset chunked with HDF5's Fletcher-32 checksum
!> filter (scalars as 1-element arrays, which h5_read_array reads as scalars): a corrupted chunk is
!> then an error on reading, never wrong values; h5_verify reads a whole file to check it (checkpoints).
!> Parallel files are handed to MPI-IO under a short name when their path is long (below).
!> Call hdf5_io_finalize once before MPI_Finalize (the library is opened on first use).
module hdf5_io
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_char, c_null_char
  use hdf5, only: hid_t, hsize_t, size_t, h5open_f, h5close_f, h5kind_to_type, H5_REAL_KIND, H5_INTEGER_KIND, &
                  h5pcreate_f, h5pclose_f, h5pset_fapl_mpio_f, h5pset_dxpl_mpio_f, h5pset_chunk_f, &
                  h5pset_fletcher32_f, h5eset_auto_f, h5gn_members_f, h5gget_obj_info_idx_f, H5G_GROUP_F, &
                  H5G_DATASET_F, h5pset_fill_time_f, H5D_FILL_TIME_NEVER_F, &
                  h5pset_libver_bounds_f, H5F_LIBVER_V18_F, H5F_LIBVER_LATEST_F, &
                  H5P_FILE_ACCESS_F, H5P_DATASET_XFER_F, H5P_DATASET_CREATE_F, &
                  H5FD_MPIO_COLLECTIVE_F, h5fcreate_f, h5fopen_f, h5fclose_f, h5fflush_f, &
                  H5F_ACC_TRUNC_F, H5F_ACC_RDWR_F, H5F_ACC_RDONLY_F, H5F_SCOPE_GLOBAL_F, &
                  h5gcreate_f, h5gclose_f, h5lexists_f, h5ldelete_f, &
                  h5dcreate_f, h5dopen_f, h5dclose_f, h5dwrite_f, h5dread_f, h5dget_space_f, h5dget_type_f, &
                  h5dset_extent_f, h5screate_f, h5screate_simple_f, h5sclose_f, h5sselect_hyperslab_f, &
                  h5sselect_none_f, h5sget_simple_extent_ndims_f, h5sget_simple_extent_npoints_f, h5sget_simple_extent_dims_f, &
                  H5S_SCALAR_F, H5S_SELECT_SET_F, H5S_UNLIMITED_F, &
                  h5tcopy_f, h5tclose_f, h5tset_size_f, h5tget_size_f, h5tset_strpad_f, H5T_FORTRAN_S1, &
                  H5T_STR_NULLPAD_F
  use mpi_f08, only: MPI_COMM_WORLD, MPI_INFO_NULL, MPI_Bcast, MPI_INTEGER8
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use file_system, only: file_exists, rename_file, short_name_t, open_short_name, close_short_name
  use parallel_env, only: my_rank, barrier, all_ranks
  implicit none
  private
  public :: h5_file_t, h5_create, h5_open, h5_close, h5_flush, h5_exists, &
            h5_write_slab, h5_read_slab, h5_write_array, h5_read_array, h5_write_string, h5_read_string, &
            h5_append, h5_truncate, h5_delete, h5_dataset_shape, h5_dataset_names, hdf5_io_finalize, h5_verify

  !> Longest path handed to MPI-IO as it is. Open MPI 4.1.4's shared-file-pointer component
  !> 'lockedfile' probes every file it opens with a lock file named <path>.locktest.<rank>, built with
  !> sprintf into a 256-byte buffer: a 228-character path worked and 229 aborted (buffer overflow,
  !> SIGABRT) on 1 and 2 ranks. A longer path is opened through a short name of the same file
  !> (file_system, short_name_t); 220 leaves room for rank numbers up to 9 digits.
  integer, parameter :: longest_direct_path = 220

  !> Longest dataset name h5_dataset_names returns (with its groups).
  integer, parameter, public :: dataset_name_length = 256

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

  !> Write a real(wp) / integer / integer(i8) scalar or array (rank 0's values).
  interface h5_write_array
    module procedure write_real_scalar, write_real_1d, write_real_2d, write_int_scalar, write_int_1d, &
                     write_int_2d, write_i8_scalar, write_i8_1d
  end interface h5_write_array

  !> Read a dataset written by h5_write_array; arrays are (re)allocated to the stored shape.
  interface h5_read_array
    module procedure read_real_scalar, read_real_1d, read_real_2d, read_int_scalar, read_int_1d, &
                     read_int_2d, read_i8_scalar, read_i8_1d
  end interface h5_read_array

  !> Append to an extendible dataset (created on first use): values(:) adds size(values) entries to a
  !> 1-D dataset; rows(:,:) adds size(rows,2) rows of width size(rows,1) to a (width, N) dataset.
  interface h5_append
    module procedure append_real_1d, append_real_2d, append_int_1d
  end interface h5_append

  logical :: library_open = .false.
  integer, parameter :: append_chunk_rows = 512   !< rows per chunk of extendible datasets
  real(wp), target :: empty_real(1) = 0.0_wp      !< buffer of ranks that take part with no data
  integer, target :: empty_int(1) = 0
  integer(i8), target :: empty_i8(1) = 0_i8

contains

  ! ---------------------------------------------------------------------------------------------
  ! Library, files, groups
  ! ---------------------------------------------------------------------------------------------

  subroutine open_library()
    integer :: status
    if (library_open) return
    call h5open_f(status)
    if (status /= 0) call fatal('hdf5_io: the HDF5 library could not be initialised (h5open_f)', collective=.false.)
    library_open = .true.
  end subroutine open_library

  !> Close the HDF5 library (every file must be closed). Call before MPI_Finalize; safe to call twice.
  subroutine hdf5_io_finalize()
    integer :: status
    if (.not. library_open) return
    call h5close_f(status)
    library_open = .false.
  end subroutine hdf5_io_finalize

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
    call fatal('hdf5_io: '//action//' failed for '//where, collective=.false.)
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
    if (.not. found) call fatal('hdf5_io: cannot open '//file%path//': no such file', collective=.not. file%serial)
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
      if (.not. all_ranks(status >= 0)) call fatal('hdf5_io: cannot open '//file%path// &
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
    call fatal('hdf5_io: cannot open '//file%path//' through MPI-IO: no short name of it within '//trim(text)// &
               ' characters (Open MPI 4.1 aborts on longer ones); a shorter file name (after the last /) is needed', &
               collective=.false.)
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
      if (.not. renamed) call fatal('hdf5_io: cannot rename '//file%path//' to '//file%complete_path, collective=.false.)
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

  subroutine require_open(file, name, for_writing)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    logical, intent(in) :: for_writing
    if (.not. file%is_open) call fatal('hdf5_io: access to '//trim(name)//' in a file that is not open', &
                                       collective=.false.)
    if (for_writing .and. .not. file%writable) &
      call fatal('hdf5_io: writing '//trim(name)//' to '//file%path//', opened read-only', collective=.false.)
  end subroutine require_open

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

  !> Open dataset name for writing with the given type and shape (Fortran order; rank 0 = scalar):
  !> an existing dataset of the same shape is reused, one of another shape replaced.
  subroutine open_for_writing(file, name, type_id, dims, dataset, maxdims, chunk)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: type_id
    integer(hsize_t), intent(in) :: dims(:)
    integer(hid_t), intent(out) :: dataset
    integer(hsize_t), intent(in), optional :: maxdims(:), chunk(:)
    integer(hid_t) :: space, properties
    integer :: status
    logical :: reuse
    integer(hsize_t), allocatable :: old_dims(:)
    call require_open(file, name, .true.)
    reuse = .false.
    if (h5_exists(file, name)) then
      old_dims = h5_dataset_shape(file, name)
      reuse = size(old_dims) == size(dims) .and. .not. present(maxdims)
      if (reuse) reuse = all(old_dims == dims)
      if (.not. reuse) then
        call h5ldelete_f(file%id, name, status)
        call require_ok(status, 'replacing a dataset of another shape', file, name)
      end if
    end if
    if (reuse) then
      call h5dopen_f(file%id, name, dataset, status)
      call require_ok(status, 'opening a dataset', file, name)
      return
    end if
    call make_parent_groups(file, name)
    if (size(dims) == 0) then
      call h5screate_f(H5S_SCALAR_F, space, status)
    else if (present(maxdims)) then
      call h5screate_simple_f(size(dims), dims, space, status, maxdims)
    else
      call h5screate_simple_f(size(dims), dims, space, status)
    end if
    call require_ok(status, 'creating a dataspace', file, name)
    if (present(chunk) .or. file%checksums .and. size(dims) > 0) then
      call h5pcreate_f(H5P_DATASET_CREATE_F, properties, status)
      if (present(chunk)) then
        call h5pset_chunk_f(properties, size(chunk), chunk, status)
      else
        call h5pset_chunk_f(properties, size(dims), checksum_chunk(dims), status)
      end if
      call require_ok(status, 'setting the chunk size', file, name)
      if (file%checksums) then
        call h5pset_fletcher32_f(properties, status)
        call require_ok(status, 'setting the Fletcher-32 filter', file, name)
        ! Every value is written: no fill values first (a parallel file allocates chunks at creation
        ! and would otherwise write each chunk twice).
        call h5pset_fill_time_f(properties, H5D_FILL_TIME_NEVER_F, status)
        call require_ok(status, 'setting the fill time', file, name)
      end if
      call h5dcreate_f(file%id, name, type_id, space, dataset, status, dcpl_id=properties)
      call h5pclose_f(properties, status)
    else
      call h5dcreate_f(file%id, name, type_id, space, dataset, status)
    end if
    call require_ok(status, 'creating a dataset', file, name)
    call h5sclose_f(space, status)
  end subroutine open_for_writing

  !> Chunk shape of a checksummed dataset: whole planes (the last index cut), as many as divide the
  !> last extent within 512 KiB (below HDF5's default 1 MiB chunk cache: 1 MiB chunks made a 64^3
  !> checkpoint on 2 ranks twice as slow). Dividing the extent keeps chunks inside the ranks' z-slabs
  !> of the usual grids (a chunk shared by two ranks costs a redistribution in parallel filtered
  !> writes). Empty extents give 1 (HDF5 needs > 0).
  pure function checksum_chunk(dims) result(chunk)
    integer(hsize_t), intent(in) :: dims(:)
    integer(hsize_t) :: chunk(size(dims))
    integer(hsize_t), parameter :: chunk_values = 65536_hsize_t   ! 512 KiB of 8-byte values
    integer :: last
    chunk = max(dims, 1_hsize_t)
    last = size(dims)
    chunk(last) = max(1_hsize_t, min(chunk(last), chunk_values / max(1_hsize_t, product(chunk(1:last - 1)))))
    do while (mod(max(dims(last), 1_hsize_t), chunk(last)) /= 0)
      chunk(last) = chunk(last) - 1_hsize_t
    end do
  end function checksum_chunk

  !> Shape of a dataset in Fortran order (size 0 for a scalar).
  function h5_dataset_shape(file, name) result(dims)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hsize_t), allocatable :: dims(:)
    integer(hid_t) :: dataset, space
    integer :: status, ndims
    integer(hsize_t), allocatable :: maxdims(:)
    call require_open(file, name, .false.)
    call h5dopen_f(file%id, name, dataset, status)
    if (status < 0) call fatal('hdf5_io: no dataset '//trim(name)//' in '//file%path, collective=.false.)
    call h5dget_space_f(dataset, space, status)
    call h5sget_simple_extent_ndims_f(space, ndims, status)
    call require_ok(status, 'reading the rank of a dataset', file, name)
    allocate(dims(ndims), maxdims(ndims))
    if (ndims > 0) then
      call h5sget_simple_extent_dims_f(space, dims, maxdims, status)
      call require_ok(status, 'reading the shape of a dataset', file, name)
    end if
    call h5sclose_f(space, status)
    call h5dclose_f(dataset, status)
  end function h5_dataset_shape

  ! ---------------------------------------------------------------------------------------------
  ! Raw transfers shared by the typed routines
  ! ---------------------------------------------------------------------------------------------

  !> Number of values rank 0 writes, known to every rank of a parallel file.
  function root_count(file, local_count) result(count)
    type(h5_file_t), intent(in) :: file
    integer, intent(in) :: local_count
    integer :: count
    integer(i8) :: shared
    count = local_count
    if (file%serial) return
    shared = int(local_count, i8)
    call MPI_Bcast(shared, 1, MPI_INTEGER8, 0, MPI_COMM_WORLD)
    count = int(shared)
  end function root_count

  !> Does this rank supply the data written by h5_write_array / h5_append?
  logical function is_writer(file)
    type(h5_file_t), intent(in) :: file
    is_writer = file%serial .or. my_rank == 0
  end function is_writer

  !> Write a whole dataset (shape dims, Fortran order) from buffer; only the writer rank's data go in.
  subroutine write_whole(file, name, type_id, dims, buffer)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: type_id
    integer(hsize_t), intent(in) :: dims(:)
    type(c_ptr), intent(in) :: buffer
    integer(hid_t) :: dataset, file_space, memory_space
    integer :: status
    if (file%checksums .and. size(dims) == 0) then   ! a scalar cannot be chunked: 1 value, checksummed
      call open_for_writing(file, name, type_id, [1_hsize_t], dataset)
    else
      call open_for_writing(file, name, type_id, dims, dataset)
    end if
    if (size(dims) > 0) then
      if (product(dims) == 0) then   ! an empty dataset has no storage to write (HDF5 rejects it)
        call h5dclose_f(dataset, status)
        return
      end if
    end if
    call h5dget_space_f(dataset, file_space, status)
    call h5dget_space_f(dataset, memory_space, status)
    if (.not. is_writer(file)) then
      call h5sselect_none_f(file_space, status)
      call h5sselect_none_f(memory_space, status)
    end if
    call h5dwrite_f(dataset, type_id, buffer, status, memory_space, file_space, file%transfer)
    call require_ok(status, 'writing a dataset', file, name)
    call h5sclose_f(memory_space, status)
    call h5sclose_f(file_space, status)
    call h5dclose_f(dataset, status)
  end subroutine write_whole

  !> Open a dataset for reading and check its rank (0 = scalar); returns its shape.
  subroutine open_for_reading(file, name, expected_rank, dataset, dims)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in) :: expected_rank
    integer(hid_t), intent(out) :: dataset
    integer(hsize_t), allocatable, intent(out) :: dims(:)
    integer :: status
    character(len=16) :: text
    call require_open(file, name, .false.)
    if (.not. h5_exists(file, name)) call fatal('hdf5_io: no dataset '//trim(name)//' in '//file%path, &
                                                collective=.false.)
    dims = h5_dataset_shape(file, name)
    if (expected_rank == 0 .and. size(dims) == 1) then   ! a scalar of a checksummed file
      if (dims(1) == 1_hsize_t) deallocate(dims)
      if (.not. allocated(dims)) allocate(dims(0))
    end if
    if (size(dims) /= expected_rank) then
      write(text, '(i0,a,i0)') size(dims), ' not ', expected_rank
      call fatal('hdf5_io: dataset '//trim(name)//' in '//file%path//' has rank '//trim(text), collective=.false.)
    end if
    call h5dopen_f(file%id, name, dataset, status)
    call require_ok(status, 'opening a dataset', file, name)
  end subroutine open_for_reading

  !> Read a whole dataset into buffer (every rank of a parallel file reads all of it, collectively).
  subroutine read_whole(file, name, dataset, type_id, buffer)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: dataset, type_id
    type(c_ptr), intent(in) :: buffer
    integer(hid_t) :: space
    integer :: status
    type(c_ptr) :: destination   ! h5dread_f takes its buffer address intent(inout)
    integer(hsize_t) :: points
    destination = buffer
    call h5dget_space_f(dataset, space, status)
    call h5sget_simple_extent_npoints_f(space, points, status)
    if (points > 0) then   ! an empty dataset has no storage to read
      call h5dread_f(dataset, type_id, destination, status, space, space, file%transfer)
      call require_ok(status, 'reading a dataset', file, name)
    end if
    call h5sclose_f(space, status)
    call h5dclose_f(dataset, status)
  end subroutine read_whole

  integer(hid_t) function real_type()
    real_type = h5kind_to_type(wp, H5_REAL_KIND)
  end function real_type

  integer(hid_t) function int_type()
    int_type = h5kind_to_type(kind(0), H5_INTEGER_KIND)
  end function int_type

  integer(hid_t) function i8_type()
    i8_type = h5kind_to_type(i8, H5_INTEGER_KIND)
  end function i8_type

  ! ---------------------------------------------------------------------------------------------
  ! Z-decomposed 3-D fields
  ! ---------------------------------------------------------------------------------------------

  !> Check a slab against its global shape; returns the file-space start and count.
  subroutine slab_selection(file, name, local_shape, z_offset, global_shape, start, count)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in) :: local_shape(3), z_offset, global_shape(3)
    integer(hsize_t), intent(out) :: start(3), count(3)
    character(len=160) :: text
    if (any(local_shape(1:2) /= global_shape(1:2)) .or. z_offset < 0 .or. &
        z_offset + local_shape(3) > global_shape(3)) then
      write(text, '(a,3(i0,1x),a,i0,a,3(i0,1x))') 'local shape ', local_shape, 'at z offset ', z_offset, &
          ' does not fit the global shape ', global_shape
      call fatal('hdf5_io: slab '//trim(name)//' of '//file%path//': '//trim(text), collective=.false.)
    end if
    start = [0_hsize_t, 0_hsize_t, int(z_offset, hsize_t)]
    count = int(local_shape, hsize_t)
  end subroutine slab_selection

  !> Collective write of a z-decomposed field: local(nx, ny, nz_local) = this rank's interior values of
  !> global planes z_offset+1 .. z_offset+nz_local of a global (nx, ny, nz) dataset.
  subroutine h5_write_slab(file, name, local, z_offset, global_shape)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), contiguous, target :: local(:,:,:)
    integer, intent(in) :: z_offset, global_shape(3)
    integer(hid_t) :: dataset, file_space, memory_space
    integer(hsize_t) :: start(3), count(3)
    integer :: status
    call slab_selection(file, name, shape(local), z_offset, global_shape, start, count)
    call open_for_writing(file, name, real_type(), int(global_shape, hsize_t), dataset)
    call h5dget_space_f(dataset, file_space, status)
    call h5screate_simple_f(3, max(count, 1_hsize_t), memory_space, status)
    if (product(count) > 0) then
      call h5sselect_hyperslab_f(file_space, H5S_SELECT_SET_F, start, count, status)
      call require_ok(status, 'selecting a slab', file, name)
      call h5dwrite_f(dataset, real_type(), c_loc(local), status, memory_space, file_space, file%transfer)
    else
      call h5sselect_none_f(file_space, status)
      call h5sselect_none_f(memory_space, status)
      call h5dwrite_f(dataset, real_type(), c_loc(empty_real), status, memory_space, file_space, file%transfer)
    end if
    call require_ok(status, 'writing a slab', file, name)
    call h5sclose_f(memory_space, status)
    call h5sclose_f(file_space, status)
    call h5dclose_f(dataset, status)
  end subroutine h5_write_slab

  !> Collective read of a z-slab of a global (nx, ny, nz) dataset into local(nx, ny, nz_local).
  !> Any decomposition works (also the whole array on every rank: z_offset = 0, nz_local = nz).
  subroutine h5_read_slab(file, name, local, z_offset, global_shape)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(out), contiguous, target :: local(:,:,:)
    integer, intent(in) :: z_offset, global_shape(3)
    integer(hid_t) :: dataset, file_space, memory_space
    integer(hsize_t) :: start(3), count(3)
    integer(hsize_t), allocatable :: dims(:)
    integer :: status
    character(len=120) :: text
    type(c_ptr) :: destination   ! h5dread_f takes its buffer address intent(inout)
    call slab_selection(file, name, shape(local), z_offset, global_shape, start, count)
    call open_for_reading(file, name, 3, dataset, dims)
    if (any(dims /= int(global_shape, hsize_t))) then
      write(text, '(a,3(i0,1x),a,3(i0,1x))') 'stored shape ', dims, 'differs from the expected ', global_shape
      call fatal('hdf5_io: slab '//trim(name)//' of '//file%path//': '//trim(text), collective=.false.)
    end if
    call h5dget_space_f(dataset, file_space, status)
    call h5screate_simple_f(3, max(count, 1_hsize_t), memory_space, status)
    if (product(count) > 0) then
      call h5sselect_hyperslab_f(file_space, H5S_SELECT_SET_F, start, count, status)
      destination = c_loc(local)
      call h5dread_f(dataset, real_type(), destination, status, memory_space, file_space, file%transfer)
    else
      call h5sselect_none_f(file_space, status)
      call h5sselect_none_f(memory_space, status)
      destination = c_loc(empty_real)
      call h5dread_f(dataset, real_type(), destination, status, memory_space, file_space, file%transfer)
    end if
    call require_ok(status, 'reading a slab', file, name)
    call h5sclose_f(memory_space, status)
    call h5sclose_f(file_space, status)
    call h5dclose_f(dataset, status)
  end subroutine h5_read_slab

  ! ---------------------------------------------------------------------------------------------
  ! Small arrays and scalars (rank 0's values written; every rank reads)
  ! ---------------------------------------------------------------------------------------------

  subroutine write_real_scalar(file, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: value
    real(wp), target :: buffer
    integer(hsize_t) :: dims(0)
    buffer = value
    call write_whole(file, name, real_type(), dims, c_loc(buffer))
  end subroutine write_real_scalar

  subroutine write_real_1d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), contiguous, target :: values(:)
    integer :: n
    n = root_count(file, size(values))
    if (is_writer(file) .and. n > 0) then
      call write_whole(file, name, real_type(), [int(n, hsize_t)], c_loc(values))
    else
      call write_whole(file, name, real_type(), [int(n, hsize_t)], c_loc(empty_real))
    end if
  end subroutine write_real_1d

  subroutine write_real_2d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), contiguous, target :: values(:,:)
    integer :: rows, columns
    rows = root_count(file, size(values, 1))
    columns = root_count(file, size(values, 2))
    if (is_writer(file) .and. rows * columns > 0) then
      call write_whole(file, name, real_type(), int([rows, columns], hsize_t), c_loc(values))
    else
      call write_whole(file, name, real_type(), int([rows, columns], hsize_t), c_loc(empty_real))
    end if
  end subroutine write_real_2d

  subroutine write_int_scalar(file, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in) :: value
    integer, target :: buffer
    integer(hsize_t) :: dims(0)
    buffer = value
    call write_whole(file, name, int_type(), dims, c_loc(buffer))
  end subroutine write_int_scalar

  subroutine write_int_1d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in), contiguous, target :: values(:)
    integer :: n
    n = root_count(file, size(values))
    if (is_writer(file) .and. n > 0) then
      call write_whole(file, name, int_type(), [int(n, hsize_t)], c_loc(values))
    else
      call write_whole(file, name, int_type(), [int(n, hsize_t)], c_loc(empty_int))
    end if
  end subroutine write_int_1d

  subroutine write_int_2d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in), contiguous, target :: values(:,:)
    integer :: rows, columns
    rows = root_count(file, size(values, 1))
    columns = root_count(file, size(values, 2))
    if (is_writer(file) .and. rows * columns > 0) then
      call write_whole(file, name, int_type(), int([rows, columns], hsize_t), c_loc(values))
    else
      call write_whole(file, name, int_type(), int([rows, columns], hsize_t), c_loc(empty_int))
    end if
  end subroutine write_int_2d

  subroutine write_i8_scalar(file, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in) :: value
    integer(i8), target :: buffer
    integer(hsize_t) :: dims(0)
    buffer = value
    call write_whole(file, name, i8_type(), dims, c_loc(buffer))
  end subroutine write_i8_scalar

  subroutine write_i8_1d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in), contiguous, target :: values(:)
    integer :: n
    n = root_count(file, size(values))
    if (is_writer(file) .and. n > 0) then
      call write_whole(file, name, i8_type(), [int(n, hsize_t)], c_loc(values))
    else
      call write_whole(file, name, i8_type(), [int(n, hsize_t)], c_loc(empty_i8))
    end if
  end subroutine write_i8_1d

  subroutine read_real_scalar(file, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(out), target :: value
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    call open_for_reading(file, name, 0, dataset, dims)
    call read_whole(file, name, dataset, real_type(), c_loc(value))
  end subroutine read_real_scalar

  subroutine read_real_1d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), allocatable, target, intent(out) :: values(:)
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    call open_for_reading(file, name, 1, dataset, dims)
    allocate(values(dims(1)))
    if (size(values) > 0) then
      call read_whole(file, name, dataset, real_type(), c_loc(values))
    else
      call read_whole(file, name, dataset, real_type(), c_loc(empty_real))
    end if
  end subroutine read_real_1d

  subroutine read_real_2d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), allocatable, target, intent(out) :: values(:,:)
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    call open_for_reading(file, name, 2, dataset, dims)
    allocate(values(dims(1), dims(2)))
    if (size(values) > 0) then
      call read_whole(file, name, dataset, real_type(), c_loc(values))
    else
      call read_whole(file, name, dataset, real_type(), c_loc(empty_real))
    end if
  end subroutine read_real_2d

  subroutine read_int_scalar(file, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(out), target :: value
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    call open_for_reading(file, name, 0, dataset, dims)
    call read_whole(file, name, dataset, int_type(), c_loc(value))
  end subroutine read_int_scalar

  subroutine read_int_1d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, allocatable, target, intent(out) :: values(:)
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    call open_for_reading(file, name, 1, dataset, dims)
    allocate(values(dims(1)))
    if (size(values) > 0) then
      call read_whole(file, name, dataset, int_type(), c_loc(values))
    else
      call read_whole(file, name, dataset, int_type(), c_loc(empty_int))
    end if
  end subroutine read_int_1d

  subroutine read_int_2d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, allocatable, target, intent(out) :: values(:,:)
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    call open_for_reading(file, name, 2, dataset, dims)
    allocate(values(dims(1), dims(2)))
    if (size(values) > 0) then
      call read_whole(file, name, dataset, int_type(), c_loc(values))
    else
      call read_whole(file, name, dataset, int_type(), c_loc(empty_int))
    end if
  end subroutine read_int_2d

  subroutine read_i8_scalar(file, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(out), target :: value
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    call open_for_reading(file, name, 0, dataset, dims)
    call read_whole(file, name, dataset, i8_type(), c_loc(value))
  end subroutine read_i8_scalar

  subroutine read_i8_1d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), allocatable, target, intent(out) :: values(:)
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    call open_for_reading(file, name, 1, dataset, dims)
    allocate(values(dims(1)))
    if (size(values) > 0) then
      call read_whole(file, name, dataset, i8_type(), c_loc(values))
    else
      call read_whole(file, name, dataset, i8_type(), c_loc(empty_i8))
    end if
  end subroutine read_i8_1d

  ! ---------------------------------------------------------------------------------------------
  ! Strings: scalar fixed-length ASCII, NUL-padded (h5py: f[name][()].decode())
  ! ---------------------------------------------------------------------------------------------

  subroutine h5_write_string(file, name, text)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name, text
    character(kind=c_char, len=:), allocatable, target :: buffer
    integer(hid_t) :: string_type
    integer :: status, length
    integer(hsize_t) :: dims(0)
    ! An HDF5 string type cannot have length 0: an empty text is stored as one NUL.
    length = root_count(file, len(text))
    allocate(character(kind=c_char, len=max(length, 1)) :: buffer)
    buffer = repeat(c_null_char, len(buffer))
    if (is_writer(file)) buffer(1:length) = text
    call h5tcopy_f(H5T_FORTRAN_S1, string_type, status)
    call h5tset_size_f(string_type, int(len(buffer), size_t), status)
    call h5tset_strpad_f(string_type, H5T_STR_NULLPAD_F, status)
    call require_ok(status, 'making a string type', file, name)
    call write_whole(file, name, string_type, dims, c_loc(buffer))
    call h5tclose_f(string_type, status)
  end subroutine h5_write_string

  subroutine h5_read_string(file, name, text)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    character(len=:), allocatable, intent(out) :: text
    character(kind=c_char, len=:), allocatable, target :: buffer
    integer(hid_t) :: dataset, stored_type, string_type
    integer(hsize_t), allocatable :: dims(:)
    integer(size_t) :: length
    integer :: status, last
    call open_for_reading(file, name, 0, dataset, dims)
    call h5dget_type_f(dataset, stored_type, status)
    call h5tget_size_f(stored_type, length, status)
    call require_ok(status, 'reading the length of a string', file, name)
    call h5tclose_f(stored_type, status)
    allocate(character(kind=c_char, len=length) :: buffer)
    call h5tcopy_f(H5T_FORTRAN_S1, string_type, status)
    call h5tset_size_f(string_type, length, status)
    call h5tset_strpad_f(string_type, H5T_STR_NULLPAD_F, status)
    call read_whole(file, name, dataset, string_type, c_loc(buffer))
    call h5tclose_f(string_type, status)
    last = index(buffer, c_null_char) - 1
    if (last < 0) last = len(buffer)
    text = buffer(1:last)
  end subroutine h5_read_string

  ! ---------------------------------------------------------------------------------------------
  ! Extendible (time-series) datasets
  ! ---------------------------------------------------------------------------------------------

  !> Append new_rows rows of width (1-D dataset when width = 0) from buffer to dataset name.
  subroutine append_rows(file, name, type_id, width, new_rows, buffer)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: type_id
    integer, intent(in) :: width, new_rows
    type(c_ptr), intent(in) :: buffer
    integer(hid_t) :: dataset, file_space, memory_space
    integer(hsize_t), allocatable :: dims(:), start(:), count(:)
    integer :: status
    character(len=80) :: text
    call require_open(file, name, .true.)
    if (.not. h5_exists(file, name)) then
      if (width == 0) then
        call open_for_writing(file, name, type_id, [0_hsize_t], dataset, maxdims=[H5S_UNLIMITED_F], &
                              chunk=[int(append_chunk_rows, hsize_t)])
      else
        call open_for_writing(file, name, type_id, [int(width, hsize_t), 0_hsize_t], dataset, &
                              maxdims=[int(width, hsize_t), H5S_UNLIMITED_F], &
                              chunk=[int(width, hsize_t), int(append_chunk_rows, hsize_t)])
      end if
      call h5dclose_f(dataset, status)
    end if
    dims = h5_dataset_shape(file, name)
    if (width == 0 .and. size(dims) /= 1 .or. width > 0 .and. size(dims) /= 2) &
      call fatal('hdf5_io: appending to '//trim(name)//' in '//file%path//': stored rank differs', &
                 collective=.false.)
    if (width > 0) then
      if (dims(1) /= int(width, hsize_t)) then
        write(text, '(a,i0,a,i0)') 'row width ', width, ' differs from the stored ', dims(1)
        call fatal('hdf5_io: appending to '//trim(name)//' in '//file%path//': '//trim(text), collective=.false.)
      end if
    end if
    if (new_rows == 0) return
    start = 0 * dims
    start(size(dims)) = dims(size(dims))
    count = dims
    count(size(dims)) = int(new_rows, hsize_t)
    dims(size(dims)) = dims(size(dims)) + int(new_rows, hsize_t)
    call h5dopen_f(file%id, name, dataset, status)
    call h5dset_extent_f(dataset, dims, status)
    call require_ok(status, 'extending a dataset', file, name)
    call h5dget_space_f(dataset, file_space, status)
    call h5screate_simple_f(size(count), count, memory_space, status)
    if (is_writer(file)) then
      call h5sselect_hyperslab_f(file_space, H5S_SELECT_SET_F, start, count, status)
    else
      call h5sselect_none_f(file_space, status)
      call h5sselect_none_f(memory_space, status)
    end if
    call h5dwrite_f(dataset, type_id, buffer, status, memory_space, file_space, file%transfer)
    call require_ok(status, 'appending to a dataset', file, name)
    call h5sclose_f(memory_space, status)
    call h5sclose_f(file_space, status)
    call h5dclose_f(dataset, status)
  end subroutine append_rows

  subroutine append_real_1d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), contiguous, target :: values(:)
    integer :: n
    n = root_count(file, size(values))
    if (is_writer(file) .and. n > 0) then
      call append_rows(file, name, real_type(), 0, n, c_loc(values))
    else
      call append_rows(file, name, real_type(), 0, n, c_loc(empty_real))
    end if
  end subroutine append_real_1d

  subroutine append_real_2d(file, name, rows)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), contiguous, target :: rows(:,:)
    integer :: width, n
    width = root_count(file, size(rows, 1))
    n = root_count(file, size(rows, 2))
    if (width < 1) call fatal('hdf5_io: appending rows of width 0 to '//trim(name), collective=.false.)
    if (is_writer(file) .and. n > 0) then
      call append_rows(file, name, real_type(), width, n, c_loc(rows))
    else
      call append_rows(file, name, real_type(), width, n, c_loc(empty_real))
    end if
  end subroutine append_real_2d

  subroutine append_int_1d(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in), contiguous, target :: values(:)
    integer :: n
    n = root_count(file, size(values))
    if (is_writer(file) .and. n > 0) then
      call append_rows(file, name, int_type(), 0, n, c_loc(values))
    else
      call append_rows(file, name, int_type(), 0, n, c_loc(empty_int))
    end if
  end subroutine append_int_1d
  !> Shrink the extendible (time-series) dataset name to its first rows rows: rows are the last
  !> Fortran index, as h5_append adds them (the columns of a 2-D table). A restarted run uses it to
  !> drop the rows an interrupted run wrote after the checkpoint it continues from. rows equal to the
  !> stored count changes nothing; more rows than stored, a scalar, or a dataset that was not made
  !> extendible (h5_append makes them chunked with an unlimited last dimension) stop with a message.
  !> Collective on a parallel file. HDF5 keeps the file space of the dropped rows; later appends reuse
  !> the allocated chunks.
  subroutine h5_truncate(file, name, rows)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in) :: rows
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    integer :: status
    character(len=80) :: text
    call require_open(file, name, .true.)
    if (.not. h5_exists(file, name)) call fatal('hdf5_io: cannot truncate '//trim(name)//' in '//file%path// &
                                                ': no such dataset', collective=.false.)
    dims = h5_dataset_shape(file, name)
    if (size(dims) == 0) call fatal('hdf5_io: cannot truncate the scalar '//trim(name)//' in '//file%path, &
                                    collective=.false.)
    if (rows < 0 .or. int(rows, hsize_t) > dims(size(dims))) then
      write(text, '(a,i0,a,i0,a)') ' to ', rows, ' rows: it holds ', dims(size(dims)), ' (allowed: 0 .. that)'
      call fatal('hdf5_io: cannot truncate '//trim(name)//' in '//file%path//trim(text), collective=.false.)
    end if
    if (int(rows, hsize_t) == dims(size(dims))) return
    dims(size(dims)) = int(rows, hsize_t)
    call h5dopen_f(file%id, name, dataset, status)
    call require_ok(status, 'opening a dataset', file, name)
    call h5dset_extent_f(dataset, dims, status)
    call require_ok(status, 'shrinking a dataset (only extendible ones can be)', file, name)
    call h5dclose_f(dataset, status)
  end subroutine h5_truncate

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
      if (len(group) + len_trim(member) > dataset_name_length) call fatal('hdf5_io: a name in '//file%path// &
          ' is longer than the listing allows: '//group//trim(member), collective=.false.)
      if (kind == H5G_GROUP_F) then
        call collect_datasets(file, group//trim(member)//'/', names)
      else if (kind == H5G_DATASET_F) then
        names = [character(len=dataset_name_length) :: names, group//trim(member)]
      end if
    end do
  end subroutine collect_datasets

  ! ---------------------------------------------------------------------------------------------
  ! Verification
  ! ---------------------------------------------------------------------------------------------

  !> Check a whole file on the calling rank alone: it opens as HDF5 and every dataset in every group
  !> reads back (with the checksums of a checksummed file verified, plane by plane). ok = .false. with
  !> the reason when not; HDF5's own error report is silenced meanwhile (a damaged file is an
  !> expected answer here, not an error of the program).
  subroutine h5_verify(path, ok, reason)
    character(len=*), intent(in) :: path
    logical, intent(out) :: ok
    character(len=:), allocatable, intent(out) :: reason
    type(h5_file_t) :: file
    integer(hid_t) :: access
    integer :: status
    call open_library()
    ok = .false.
    reason = ''
    if (.not. file_exists(path)) then
      reason = 'no such file'
      return
    end if
    call h5eset_auto_f(0, status)
    file%path = trim(path)
    file%serial = .true.
    call make_property_lists(file, access)
    call h5fopen_f(file%path, H5F_ACC_RDONLY_F, file%id, status, access_prp=access)
    call h5pclose_f(access, status)
    if (status < 0) then
      reason = 'not a readable HDF5 file (truncated or overwritten?)'
    else
      file%is_open = .true.
      call verify_group(file, '/', ok, reason)
      call h5pclose_f(file%transfer, status)
      call h5fclose_f(file%id, status)
      if (ok .and. status < 0) then
        ok = .false.
        reason = 'the file does not close cleanly'
      end if
    end if
    call h5eset_auto_f(1, status)
  end subroutine h5_verify

  !> Read every dataset below group (recursively); stops at the first failure.
  recursive subroutine verify_group(file, group, ok, reason)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: group
    logical, intent(out) :: ok
    character(len=:), allocatable, intent(inout) :: reason
    character(len=256) :: member
    integer :: members, i, kind, status
    ok = .false.
    call h5gn_members_f(file%id, group, members, status)
    if (status < 0) then
      reason = 'cannot list group '//group
      return
    end if
    do i = 0, members - 1
      call h5gget_obj_info_idx_f(file%id, group, i, member, kind, status)
      if (status < 0) then
        reason = 'cannot read the entries of group '//group
        return
      end if
      if (kind == H5G_GROUP_F) then
        call verify_group(file, group//trim(member)//'/', ok, reason)
      else if (kind == H5G_DATASET_F) then
        call verify_dataset(file, group//trim(member), ok, reason)
      else
        ok = .true.
      end if
      if (.not. ok) return
    end do
    ok = .true.
  end subroutine verify_group

  !> Read a dataset of any type and shape, one plane (last index) at a time, as raw bytes.
  subroutine verify_dataset(file, name, ok, reason)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    logical, intent(out) :: ok
    character(len=:), allocatable, intent(inout) :: reason
    integer(hid_t) :: dataset, stored_type, file_space, memory_space
    integer(hsize_t), allocatable :: dims(:), maxdims(:), start(:), count(:)
    integer(size_t) :: value_bytes
    integer(hsize_t) :: plane, k
    integer(kind=1), allocatable, target :: buffer(:)
    type(c_ptr) :: destination   ! h5dread_f takes its buffer address intent(inout)
    integer :: status, ndims, closed
    ok = .false.
    reason = 'cannot read dataset '//name
    call h5dopen_f(file%id, name, dataset, status)
    if (status < 0) return
    call h5dget_type_f(dataset, stored_type, status)
    call h5tget_size_f(stored_type, value_bytes, status)
    call h5dget_space_f(dataset, file_space, status)
    call h5sget_simple_extent_ndims_f(file_space, ndims, status)
    allocate(dims(ndims), maxdims(ndims))
    if (ndims > 0) call h5sget_simple_extent_dims_f(file_space, dims, maxdims, status)
    if (status >= 0) then
      if (ndims == 0) then
        allocate(buffer(value_bytes))
        destination = c_loc(buffer)
        call h5dread_f(dataset, stored_type, destination, status)
      else if (product(dims) == 0) then
        status = 0
      else
        count = dims
        count(ndims) = 1
        start = 0 * dims
        plane = product(count)
        allocate(buffer(plane * value_bytes))
        destination = c_loc(buffer)
        call h5screate_simple_f(ndims, count, memory_space, status)
        do k = 0, dims(ndims) - 1
          start(ndims) = k
          call h5sselect_hyperslab_f(file_space, H5S_SELECT_SET_F, start, count, status)
          if (status < 0) exit
          call h5dread_f(dataset, stored_type, destination, status, memory_space, file_space)
          if (status < 0) exit
        end do
        call h5sclose_f(memory_space, closed)
      end if
    end if
    if (status >= 0) ok = .true.
    if (ok) reason = ''
    call h5sclose_f(file_space, closed)
    call h5tclose_f(stored_type, closed)
    call h5dclose_f(dataset, closed)
  end subroutine verify_dataset
end module hdf5_io
