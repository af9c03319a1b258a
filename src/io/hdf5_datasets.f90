!> Whole datasets and z-slabs of the files of hdf5_files.
!>
!> On a parallel file every call is COLLECTIVE. Raw data move with collective MPI-IO transfers. For
!> h5_write_array the values of rank 0 are written (the other ranks take part with an empty
!> selection); h5_read_array / h5_read_scalar give every rank the values. h5_write_slab /
!> h5_read_slab move z-decomposed 3-D fields, each rank its own planes.
!>
!> One generic path for every type and rank: h5_write_array and h5_read_array take assumed-rank
!> arrays (dimension(..)) of real(wp), integer and integer(i8) and hand their address (c_loc) and
!> shape to one routine that writes or reads any dataset; only allocating the array read needs its
!> rank (select rank). Scalars are written by h5_write_array too; h5_read_scalar reads them into a
!> plain variable (an assumed-rank allocatable cannot receive one).
!>
!> Array shapes are given in Fortran order: h5dump and h5py show them reversed (a Fortran
!> (nx, ny, nz) dataset is (nz, ny, nx) in h5py). In a file created with checksums = .true. every
!> dataset is stored chunked with the Fletcher-32 filter (scalars as 1-element arrays, which
!> h5_read_scalar reads as scalars).
module hdf5_datasets
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_char, c_null_char
  use hdf5, only: hid_t, hsize_t, size_t, h5kind_to_type, H5_REAL_KIND, H5_INTEGER_KIND, h5pcreate_f, h5pclose_f, &
                  h5pset_chunk_f, h5pset_fletcher32_f, h5pset_fill_time_f, H5D_FILL_TIME_NEVER_F, H5P_DATASET_CREATE_F, &
                  h5ldelete_f, h5dcreate_f, h5dopen_f, h5dclose_f, h5dwrite_f, h5dread_f, h5dget_space_f, h5dget_type_f, &
                  h5screate_f, h5screate_simple_f, h5sclose_f, h5sselect_hyperslab_f, h5sselect_none_f, &
                  h5sget_simple_extent_ndims_f, h5sget_simple_extent_npoints_f, h5sget_simple_extent_dims_f, &
                  H5S_SCALAR_F, H5S_SELECT_SET_F, h5tcopy_f, h5tclose_f, h5tset_size_f, h5tget_size_f, h5tset_strpad_f, &
                  H5T_FORTRAN_S1, H5T_STR_NULLPAD_F
  use mpi_f08, only: MPI_COMM_WORLD, MPI_Bcast, MPI_INTEGER8
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use parallel_env, only: my_rank
  use hdf5_files, only: h5_file_t, h5_exists, require_ok, require_open, make_parent_groups
  implicit none
  private
  public :: h5_write_array, h5_read_array, h5_read_scalar, h5_write_string, h5_read_string, h5_write_slab, &
            h5_read_slab, h5_dataset_shape
  ! For hdf5_series:
  public :: open_for_writing, root_shape, is_writer, real_type, int_type

  !> Write a real(wp) / integer / integer(i8) scalar or array of any rank (rank 0's values).
  interface h5_write_array
    module procedure write_real, write_int, write_i8
  end interface h5_write_array

  !> Read a dataset written by h5_write_array into an allocatable array of rank 1 to 3, (re)allocated
  !> to the stored shape.
  interface h5_read_array
    module procedure read_real, read_int, read_i8
  end interface h5_read_array

  !> Read a scalar written by h5_write_array.
  interface h5_read_scalar
    module procedure read_real_scalar, read_int_scalar, read_i8_scalar
  end interface h5_read_scalar

contains

  ! ---------------------------------------------------------------------------------------------
  ! Datasets of any type and shape, through their address
  ! ---------------------------------------------------------------------------------------------

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
    if (status < 0) call fatal('hdf5: no dataset '//trim(name)//' in '//file%path, collective=.false.)
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

  !> The shape of the values rank 0 writes, known to every rank of a parallel file. Extents below 0
  !> count as 0: gfortran 12 gives an empty array expression (such as [integer ::]) passed to an
  !> assumed-rank dummy the extent -1.
  function root_shape(file, local_shape) result(dims)
    type(h5_file_t), intent(in) :: file
    integer, intent(in) :: local_shape(:)
    integer(hsize_t), allocatable :: dims(:)
    integer(i8) :: shared(size(local_shape))
    shared = int(max(local_shape, 0), i8)
    if (.not. file%serial .and. size(shared) > 0) call MPI_Bcast(shared, size(shared), MPI_INTEGER8, 0, MPI_COMM_WORLD)
    dims = int(shared, hsize_t)
  end function root_shape

  !> Does this rank supply the data written by h5_write_array / h5_append?
  logical function is_writer(file)
    type(h5_file_t), intent(in) :: file
    is_writer = file%serial .or. my_rank == 0
  end function is_writer

  !> Write a whole dataset from the values at address, of shape local_shape on rank 0 (which alone
  !> supplies data; the other ranks' address is never read).
  subroutine write_values(file, name, type_id, local_shape, address)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: type_id
    integer, intent(in) :: local_shape(:)
    type(c_ptr), intent(in) :: address
    integer(hid_t) :: dataset, file_space, memory_space
    integer(hsize_t), allocatable :: dims(:)
    integer :: status
    dims = root_shape(file, local_shape)
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
    call h5dwrite_f(dataset, type_id, address, status, memory_space, file_space, file%transfer)
    call require_ok(status, 'writing a dataset', file, name)
    call h5sclose_f(memory_space, status)
    call h5sclose_f(file_space, status)
    call h5dclose_f(dataset, status)
  end subroutine write_values

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
    if (.not. h5_exists(file, name)) call fatal('hdf5: no dataset '//trim(name)//' in '//file%path, &
                                                collective=.false.)
    dims = h5_dataset_shape(file, name)
    if (expected_rank == 0 .and. size(dims) == 1) then   ! a scalar of a checksummed file
      if (dims(1) == 1_hsize_t) deallocate(dims)
      if (.not. allocated(dims)) allocate(dims(0))
    end if
    if (size(dims) /= expected_rank) then
      write(text, '(i0,a,i0)') size(dims), ' not ', expected_rank
      call fatal('hdf5: dataset '//trim(name)//' in '//file%path//' has rank '//trim(text), collective=.false.)
    end if
    call h5dopen_f(file%id, name, dataset, status)
    call require_ok(status, 'opening a dataset', file, name)
  end subroutine open_for_reading

  !> Read a whole dataset to address (every rank of a parallel file reads all of it, collectively).
  subroutine read_values(file, name, dataset, type_id, address)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: dataset, type_id
    type(c_ptr), intent(in) :: address
    integer(hid_t) :: space
    integer :: status
    type(c_ptr) :: destination   ! h5dread_f takes its buffer address intent(inout)
    integer(hsize_t) :: points
    destination = address
    call h5dget_space_f(dataset, space, status)
    call h5sget_simple_extent_npoints_f(space, points, status)
    if (points > 0) then   ! an empty dataset has no storage to read
      call h5dread_f(dataset, type_id, destination, status, space, space, file%transfer)
      call require_ok(status, 'reading a dataset', file, name)
    end if
    call h5sclose_f(space, status)
    call h5dclose_f(dataset, status)
  end subroutine read_values

  !> Stop for an array rank h5_read_array does not allocate.
  subroutine unsupported_rank(file, name, array_rank)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in) :: array_rank
    character(len=16) :: text
    write(text, '(i0)') array_rank
    call fatal('hdf5: reading '//trim(name)//' of '//file%path//' into an array of rank '//trim(text)// &
               ' (h5_read_array reads ranks 1 to 3; h5_read_scalar reads scalars)', collective=.false.)
  end subroutine unsupported_rank

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
  ! The typed entry points: the address and shape of the caller's variable (an empty array has no
  ! address, c_loc needs a non-empty one: a one-value local stands in, never read or written)
  ! ---------------------------------------------------------------------------------------------

  subroutine write_real(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), contiguous, target :: values(..)
    real(wp), target :: nothing(1)
    if (size(values) > 0) then
      call write_values(file, name, real_type(), shape(values), c_loc(values))
    else
      call write_values(file, name, real_type(), shape(values), c_loc(nothing))
    end if
  end subroutine write_real

  subroutine write_int(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in), contiguous, target :: values(..)
    integer, target :: nothing(1)
    if (size(values) > 0) then
      call write_values(file, name, int_type(), shape(values), c_loc(values))
    else
      call write_values(file, name, int_type(), shape(values), c_loc(nothing))
    end if
  end subroutine write_int

  subroutine write_i8(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(in), contiguous, target :: values(..)
    integer(i8), target :: nothing(1)
    if (size(values) > 0) then
      call write_values(file, name, i8_type(), shape(values), c_loc(values))
    else
      call write_values(file, name, i8_type(), shape(values), c_loc(nothing))
    end if
  end subroutine write_i8

  subroutine read_real(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), allocatable, target, intent(out) :: values(..)
    real(wp), target :: nothing(1)
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: d(:)
    call open_for_reading(file, name, rank(values), dataset, d)
    select rank (values)
    rank (1)
      allocate(values(d(1)))
    rank (2)
      allocate(values(d(1), d(2)))
    rank (3)
      allocate(values(d(1), d(2), d(3)))
    rank default
      call unsupported_rank(file, name, rank(values))
    end select
    if (size(values) > 0) then
      call read_values(file, name, dataset, real_type(), c_loc(values))
    else
      call read_values(file, name, dataset, real_type(), c_loc(nothing))
    end if
  end subroutine read_real

  subroutine read_int(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, allocatable, target, intent(out) :: values(..)
    integer, target :: nothing(1)
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: d(:)
    call open_for_reading(file, name, rank(values), dataset, d)
    select rank (values)
    rank (1)
      allocate(values(d(1)))
    rank (2)
      allocate(values(d(1), d(2)))
    rank (3)
      allocate(values(d(1), d(2), d(3)))
    rank default
      call unsupported_rank(file, name, rank(values))
    end select
    if (size(values) > 0) then
      call read_values(file, name, dataset, int_type(), c_loc(values))
    else
      call read_values(file, name, dataset, int_type(), c_loc(nothing))
    end if
  end subroutine read_int

  subroutine read_i8(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), allocatable, target, intent(out) :: values(..)
    integer(i8), target :: nothing(1)
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: d(:)
    call open_for_reading(file, name, rank(values), dataset, d)
    select rank (values)
    rank (1)
      allocate(values(d(1)))
    rank (2)
      allocate(values(d(1), d(2)))
    rank (3)
      allocate(values(d(1), d(2), d(3)))
    rank default
      call unsupported_rank(file, name, rank(values))
    end select
    if (size(values) > 0) then
      call read_values(file, name, dataset, i8_type(), c_loc(values))
    else
      call read_values(file, name, dataset, i8_type(), c_loc(nothing))
    end if
  end subroutine read_i8

  !> Read the scalar dataset name of type type_id to address.
  subroutine read_scalar(file, name, type_id, address)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: type_id
    type(c_ptr), intent(in) :: address
    integer(hid_t) :: dataset
    integer(hsize_t), allocatable :: dims(:)
    call open_for_reading(file, name, 0, dataset, dims)
    call read_values(file, name, dataset, type_id, address)
  end subroutine read_scalar

  subroutine read_real_scalar(file, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(out), target :: value
    call read_scalar(file, name, real_type(), c_loc(value))
  end subroutine read_real_scalar

  subroutine read_int_scalar(file, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(out), target :: value
    call read_scalar(file, name, int_type(), c_loc(value))
  end subroutine read_int_scalar

  subroutine read_i8_scalar(file, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(i8), intent(out), target :: value
    call read_scalar(file, name, i8_type(), c_loc(value))
  end subroutine read_i8_scalar

  ! ---------------------------------------------------------------------------------------------
  ! Strings: scalar fixed-length ASCII, NUL-padded (h5py: f[name][()].decode())
  ! ---------------------------------------------------------------------------------------------

  subroutine h5_write_string(file, name, text)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name, text
    character(kind=c_char, len=:), allocatable, target :: buffer
    integer(hid_t) :: string_type
    integer :: status, length
    integer(hsize_t), allocatable :: dims(:)
    ! An HDF5 string type cannot have length 0: an empty text is stored as one NUL.
    dims = root_shape(file, [len(text)])
    length = int(dims(1))
    allocate(character(kind=c_char, len=max(length, 1)) :: buffer)
    buffer = repeat(c_null_char, len(buffer))
    if (is_writer(file)) buffer(1:length) = text
    call h5tcopy_f(H5T_FORTRAN_S1, string_type, status)
    call h5tset_size_f(string_type, int(len(buffer), size_t), status)
    call h5tset_strpad_f(string_type, H5T_STR_NULLPAD_F, status)
    call require_ok(status, 'making a string type', file, name)
    call write_values(file, name, string_type, [integer ::], c_loc(buffer))
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
    call read_values(file, name, dataset, string_type, c_loc(buffer))
    call h5tclose_f(string_type, status)
    last = index(buffer, c_null_char) - 1
    if (last < 0) last = len(buffer)
    text = buffer(1:last)
  end subroutine h5_read_string

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
      call fatal('hdf5: slab '//trim(name)//' of '//file%path//': '//trim(text), collective=.false.)
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
    real(wp), target :: nothing(1)   ! the buffer of a rank without planes (never read)
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
      call h5dwrite_f(dataset, real_type(), c_loc(nothing), status, memory_space, file_space, file%transfer)
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
    real(wp), target :: nothing(1)   ! the buffer of a rank without planes (never written)
    type(c_ptr) :: destination       ! h5dread_f takes its buffer address intent(inout)
    call slab_selection(file, name, shape(local), z_offset, global_shape, start, count)
    call open_for_reading(file, name, 3, dataset, dims)
    if (any(dims /= int(global_shape, hsize_t))) then
      write(text, '(a,3(i0,1x),a,3(i0,1x))') 'stored shape ', dims, 'differs from the expected ', global_shape
      call fatal('hdf5: slab '//trim(name)//' of '//file%path//': '//trim(text), collective=.false.)
    end if
    call h5dget_space_f(dataset, file_space, status)
    call h5screate_simple_f(3, max(count, 1_hsize_t), memory_space, status)
    if (product(count) > 0) then
      call h5sselect_hyperslab_f(file_space, H5S_SELECT_SET_F, start, count, status)
      destination = c_loc(local)
    else
      call h5sselect_none_f(file_space, status)
      call h5sselect_none_f(memory_space, status)
      destination = c_loc(nothing)
    end if
    call h5dread_f(dataset, real_type(), destination, status, memory_space, file_space, file%transfer)
    call require_ok(status, 'reading a slab', file, name)
    call h5sclose_f(memory_space, status)
    call h5sclose_f(file_space, status)
    call h5dclose_f(dataset, status)
  end subroutine h5_read_slab
end module hdf5_datasets
