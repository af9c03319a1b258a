!> Verification of a whole HDF5 file (checkpoints before a restart): it opens, and every dataset of
!> every group reads back, with the Fletcher-32 checksums of a checksummed file (hdf5_datasets)
!> verified. A damaged file is an answer here (ok = .false. and the reason), not an error.
module hdf5_checks
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc
  use hdf5, only: hid_t, hsize_t, size_t, h5eset_auto_f, h5fopen_f, h5fclose_f, H5F_ACC_RDONLY_F, h5pclose_f, &
                  h5gn_members_f, h5gget_obj_info_idx_f, H5G_GROUP_F, H5G_DATASET_F, h5dopen_f, h5dclose_f, &
                  h5dread_f, h5dget_space_f, h5dget_type_f, h5tget_size_f, h5tclose_f, h5screate_simple_f, &
                  h5sclose_f, h5sselect_hyperslab_f, h5sget_simple_extent_ndims_f, h5sget_simple_extent_dims_f, &
                  H5S_SELECT_SET_F
  use file_system, only: file_exists
  use hdf5_files, only: h5_file_t, open_library, make_property_lists, dataset_name_length
  implicit none
  private
  public :: h5_verify

contains

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
    integer :: status, opened
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
    call h5fopen_f(file%path, H5F_ACC_RDONLY_F, file%id, opened, access_prp=access)
    call h5pclose_f(access, status)
    if (opened < 0) then
      reason = 'not a readable HDF5 file (truncated or overwritten?)'
      call h5pclose_f(file%transfer, status)
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
    character(len=dataset_name_length) :: member
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
end module hdf5_checks
