!> Extendible (time-series) datasets of the files of hdf5_files: rows appended as a run goes, and
!> cut back to a checkpoint's row count when a run continues. Rows are the last Fortran index: a 1-D
!> dataset grows by values, a (width, N) dataset by columns of width values. On a parallel file every
!> call is COLLECTIVE and rank 0's values are written.
module hdf5_series
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc
  use hdf5, only: hid_t, hsize_t, h5dopen_f, h5dclose_f, h5dwrite_f, h5dget_space_f, h5dset_extent_f, &
                  h5screate_simple_f, h5sclose_f, h5sselect_hyperslab_f, h5sselect_none_f, H5S_SELECT_SET_F, &
                  H5S_UNLIMITED_F
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use hdf5_files, only: h5_file_t, h5_exists, require_ok, require_open
  use hdf5_datasets, only: h5_dataset_shape, open_for_writing, root_shape, is_writer, real_type, int_type
  implicit none
  private
  public :: h5_append, h5_truncate

  !> Append to an extendible dataset (created on first use): values(:) adds size(values) entries to a
  !> 1-D dataset; rows(:,:) adds size(rows,2) rows of width size(rows,1) to a (width, N) dataset.
  interface h5_append
    module procedure append_real, append_int
  end interface h5_append

  !> rows per chunk of extendible datasets; rows of more than 32 values: 16384 values per chunk (a
  !> first chunk of a wide row, e.g. every body of a suspension, stays 128 KiB)
  integer, parameter :: append_chunk_rows = 512

contains

  !> Append the rows of rank 0's values at address (shape local_shape: (n) or (width, n)).
  subroutine append_values(file, name, type_id, local_shape, address)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: type_id
    integer, intent(in) :: local_shape(:)
    type(c_ptr), intent(in) :: address
    integer(hsize_t), allocatable :: dims(:)
    if (size(local_shape) < 1 .or. size(local_shape) > 2) call fatal('hdf5: appending to '//trim(name)// &
        ' of '//file%path//': h5_append takes values(:) or rows(:,:)', collective=.false.)
    dims = root_shape(file, local_shape)
    if (size(dims) == 1) then
      call append_rows(file, name, type_id, 0, int(dims(1)), address)
    else
      if (dims(1) < 1) call fatal('hdf5: appending rows of width 0 to '//trim(name), collective=.false.)
      call append_rows(file, name, type_id, int(dims(1)), int(dims(2)), address)
    end if
  end subroutine append_values

  !> Append new_rows rows of width (1-D dataset when width = 0) from address to dataset name.
  subroutine append_rows(file, name, type_id, width, new_rows, address)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer(hid_t), intent(in) :: type_id
    integer, intent(in) :: width, new_rows
    type(c_ptr), intent(in) :: address
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
                              chunk=[int(width, hsize_t), int(max(1, min(append_chunk_rows, 16384 / width)), hsize_t)])
      end if
      call h5dclose_f(dataset, status)
    end if
    dims = h5_dataset_shape(file, name)
    if (width == 0 .and. size(dims) /= 1 .or. width > 0 .and. size(dims) /= 2) &
      call fatal('hdf5: appending to '//trim(name)//' in '//file%path//': stored rank differs', &
                 collective=.false.)
    if (width > 0) then
      if (dims(1) /= int(width, hsize_t)) then
        write(text, '(a,i0,a,i0)') 'row width ', width, ' differs from the stored ', dims(1)
        call fatal('hdf5: appending to '//trim(name)//' in '//file%path//': '//trim(text), collective=.false.)
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
    call h5dwrite_f(dataset, type_id, address, status, memory_space, file_space, file%transfer)
    call require_ok(status, 'appending to a dataset', file, name)
    call h5sclose_f(memory_space, status)
    call h5sclose_f(file_space, status)
    call h5dclose_f(dataset, status)
  end subroutine append_rows

  ! The typed entry points (an empty array has no address: a one-value local stands in, never read).

  subroutine append_real(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(in), contiguous, target :: values(..)
    real(wp), target :: nothing(1)
    if (size(values) > 0) then
      call append_values(file, name, real_type(), shape(values), c_loc(values))
    else
      call append_values(file, name, real_type(), shape(values), c_loc(nothing))
    end if
  end subroutine append_real

  subroutine append_int(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(in), contiguous, target :: values(..)
    integer, target :: nothing(1)
    if (size(values) > 0) then
      call append_values(file, name, int_type(), shape(values), c_loc(values))
    else
      call append_values(file, name, int_type(), shape(values), c_loc(nothing))
    end if
  end subroutine append_int

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
    if (.not. h5_exists(file, name)) call fatal('hdf5: cannot truncate '//trim(name)//' in '//file%path// &
                                                ': no such dataset', collective=.false.)
    dims = h5_dataset_shape(file, name)
    if (size(dims) == 0) call fatal('hdf5: cannot truncate the scalar '//trim(name)//' in '//file%path, &
                                    collective=.false.)
    if (rows < 0 .or. int(rows, hsize_t) > dims(size(dims))) then
      write(text, '(a,i0,a,i0,a)') ' to ', rows, ' rows: it holds ', dims(size(dims)), ' (allowed: 0 .. that)'
      call fatal('hdf5: cannot truncate '//trim(name)//' in '//file%path//trim(text), collective=.false.)
    end if
    if (int(rows, hsize_t) == dims(size(dims))) return
    dims(size(dims)) = int(rows, hsize_t)
    call h5dopen_f(file%id, name, dataset, status)
    call require_ok(status, 'opening a dataset', file, name)
    call h5dset_extent_f(dataset, dims, status)
    call require_ok(status, 'shrinking a dataset (only extendible ones can be)', file, name)
    call h5dclose_f(dataset, status)
  end subroutine h5_truncate
end module hdf5_series
