! ranks: 2
! checks: 33
!> Unit tests of the HDF5 layer (hdf5_files, hdf5_datasets, hdf5_series) on 2 ranks: a z-decomposed
!> field written collectively and read back bit for bit on the same and on another decomposition
!> (whole array on every rank, uneven split), scalars, arrays and strings round trip, nested groups,
!> extendible datasets, serial files on one rank.
!> Reference: the written values themselves (HDF5 stores IEEE doubles unchanged: exact equality).
program test_hdf5_io
  use agglo_kinds, only: wp, i8
  use hdf5, only: hsize_t
  use hdf5_files, only: h5_file_t, h5_create, h5_open, h5_close, h5_exists, h5_delete, h5_finalize
  use hdf5_datasets, only: h5_read_scalar, h5_write_slab, h5_read_slab, h5_write_array, h5_read_array, h5_write_string, &
                           h5_read_string, h5_dataset_shape
  use hdf5_series, only: h5_append, h5_truncate
  use parallel_env, only: parallel_start, my_rank, n_ranks, barrier, is_root
  use file_system, only: delete_file
  use test_framework, only: test_start, test_finish, check, check_equal
  implicit none
  integer, parameter :: nx = 6, ny = 5, nz = 8
  character(len=*), parameter :: path = 'test_hdf5_io.h5', serial_path = 'test_hdf5_io_serial.h5'
  type(h5_file_t) :: file
  real(wp), allocatable :: local(:,:,:), whole(:,:,:), back(:,:,:), reals(:), table(:,:)
  integer, allocatable :: ints(:), cube(:,:,:)
  integer(i8), allocatable :: longs(:)
  integer(hsize_t), allocatable :: dims(:)
  character(len=:), allocatable :: text
  real(wp) :: x
  integer :: n, k_first, nz_local, z_offset, i, j, k
  integer(i8) :: long
  logical :: same

  call parallel_start()
  call test_start('hdf5_io')
  call check(n_ranks == 2, 'runs_on_2_ranks', 'the decomposition checks below need 2 ranks')

  ! Global reference field: a value that differs in every cell and in the last bits.
  allocate(whole(nx, ny, nz))
  do k = 1, nz
    do j = 1, ny
      do i = 1, nx
        whole(i, j, k) = sin(real(i + 10 * j + 100 * k, wp)) / 3.0_wp
      end do
    end do
  end do

  ! Even split along z: rank r holds planes r*nz/2 + 1 .. (r+1)*nz/2.
  nz_local = nz / n_ranks
  z_offset = my_rank * nz_local
  local = whole(:, :, z_offset + 1:z_offset + nz_local)
  call h5_create(file, path)
  call h5_write_slab(file, 'fluid/u', local, z_offset, [nx, ny, nz])
  call h5_write_array(file, 'time', 1.25_wp)
  call h5_write_array(file, 'step', 42)
  call h5_write_array(file, 'step_i8', 12345678901_i8)
  call h5_write_array(file, 'deep/a/b/reals', [1.0_wp / 3.0_wp, -2.5e-300_wp, huge(1.0_wp)])
  call h5_write_array(file, 'deep/a/ints', [3, -4, 5, 6])
  call h5_write_array(file, 'deep/rng', [huge(1_i8), -7_i8])
  call h5_write_array(file, 'table', reshape([(real(i, wp), i = 1, 6)], [3, 2]))
  call h5_write_array(file, 'cube', reshape([(i, i = 1, 24)], [2, 3, 4]))   ! any rank, any type
  ! Rank 0's values are written whatever the other ranks pass.
  call h5_write_array(file, 'root_value', real(my_rank + 7, wp))
  call h5_write_array(file, 'empty', [integer ::])
  call h5_write_string(file, 'meta/shape', 'needle  ')
  call h5_write_string(file, 'meta/empty', '')
  call h5_close(file)

  ! Read back on the same decomposition: bit for bit.
  call h5_open(file, path, writable=.false.)
  allocate(back(nx, ny, nz_local))
  call h5_read_slab(file, 'fluid/u', back, z_offset, [nx, ny, nz])
  call check(all(back == local), 'slab_round_trip_same_decomposition')
  deallocate(back)

  ! Whole array on every rank (overlapping collective reads).
  allocate(back(nx, ny, nz))
  call h5_read_slab(file, 'fluid/u', back, 0, [nx, ny, nz])
  call check(all(back == whole), 'slab_read_whole_on_every_rank')
  deallocate(back)

  ! Uneven split: rank 0 reads 3 planes, rank 1 the other 5.
  k_first = merge(0, 3, my_rank == 0)
  n = merge(3, nz - 3, my_rank == 0)
  allocate(back(nx, ny, n))
  call h5_read_slab(file, 'fluid/u', back, k_first, [nx, ny, nz])
  call check(all(back == whole(:, :, k_first + 1:k_first + n)), 'slab_read_other_decomposition')
  deallocate(back)

  ! A rank with no planes takes part with an empty selection.
  n = merge(nz, 0, my_rank == 0)
  allocate(back(nx, ny, n))
  call h5_read_slab(file, 'fluid/u', back, 0, [nx, ny, nz])
  same = .true.
  if (n > 0) same = all(back == whole)
  call check(same, 'slab_read_with_an_empty_rank')
  deallocate(back)

  call h5_read_scalar(file, 'time', x)
  call check(x == 1.25_wp, 'real_scalar_round_trip')
  call h5_read_scalar(file, 'step', n)
  call check_equal(n, 42, 'int_scalar_round_trip')
  call h5_read_scalar(file, 'step_i8', long)
  call check(long == 12345678901_i8, 'i8_scalar_round_trip')
  call h5_read_array(file, 'deep/a/b/reals', reals)
  call check(size(reals) == 3, 'real_array_size')
  call check(all(reals == [1.0_wp / 3.0_wp, -2.5e-300_wp, huge(1.0_wp)]), 'real_array_round_trip_bit_exact')
  call h5_read_array(file, 'deep/a/ints', ints)
  call check(all(ints == [3, -4, 5, 6]), 'int_array_round_trip')
  call h5_read_array(file, 'deep/rng', longs)
  call check(all(longs == [huge(1_i8), -7_i8]), 'i8_array_round_trip')
  call h5_read_array(file, 'table', table)
  call check(all(shape(table) == [3, 2]) .and. table(3, 2) == 6.0_wp .and. table(1, 2) == 4.0_wp, &
             'real_2d_round_trip_fortran_order')
  call h5_read_array(file, 'cube', cube)
  call check(all(shape(cube) == [2, 3, 4]) .and. all(cube == reshape([(i, i = 1, 24)], [2, 3, 4])), &
             'int_3d_round_trip_fortran_order')
  call h5_read_scalar(file, 'root_value', x)
  call check(x == 7.0_wp, 'root_values_written_every_rank_reads', 'rank 0 wrote 7')
  call h5_read_array(file, 'empty', ints)
  call check(size(ints) == 0, 'empty_array_round_trip')
  call h5_read_string(file, 'meta/shape', text)
  call check(text == 'needle  ' .and. len(text) == 8, 'string_round_trip_keeps_trailing_blanks', '['//text//']')
  call h5_read_string(file, 'meta/empty', text)
  call check(len(text) == 0, 'empty_string_round_trip')
  call check(h5_exists(file, 'deep/a/b') .and. h5_exists(file, 'deep/a/b/reals') .and. h5_exists(file, '/fluid/u'), &
             'nested_groups_created')
  call check(.not. h5_exists(file, 'missing/group/x') .and. .not. h5_exists(file, 'deep/nothing'), &
             'missing_names_not_found')
  call h5_close(file)

  ! Rewrite in place with another shape, then append time-series rows collectively.
  call h5_open(file, path, writable=.true.)
  call h5_write_array(file, 'deep/a/ints', [9])
  call h5_append(file, 'series/time', [0.5_wp])
  call h5_append(file, 'series/time', [1.0_wp, 1.5_wp])
  call h5_append(file, 'series/position', reshape([1.0_wp, 2.0_wp, 3.0_wp], [3, 1]))
  call h5_append(file, 'series/position', reshape([4.0_wp, 5.0_wp, 6.0_wp, 7.0_wp, 8.0_wp, 9.0_wp], [3, 2]))
  call h5_append(file, 'series/count', [1, 2])
  call h5_close(file)
  call h5_open(file, path, writable=.false.)
  call h5_read_array(file, 'deep/a/ints', ints)
  call check(size(ints) == 1 .and. ints(1) == 9, 'rewrite_with_another_shape')
  call h5_read_array(file, 'series/time', reals)
  call check(size(reals) == 3 .and. all(reals == [0.5_wp, 1.0_wp, 1.5_wp]), 'append_1d_rows')
  call h5_read_array(file, 'series/position', table)
  call check(all(shape(table) == [3, 3]) .and. all(table(:, 3) == [7.0_wp, 8.0_wp, 9.0_wp]), 'append_2d_rows')
  dims = h5_dataset_shape(file, 'series/position')
  call check(size(dims) == 2 .and. dims(2) == 3, 'dataset_shape_fortran_order')
  call h5_read_array(file, 'series/count', ints)
  call check(all(ints == [1, 2]), 'append_int_rows')
  call h5_close(file)

  ! A restart drops the rows written after its checkpoint (h5_truncate) and the per-row datasets
  ! (h5_delete), then appends again: the new rows must follow the kept ones, as in one run.
  call h5_open(file, path, writable=.true.)
  call h5_truncate(file, 'series/time', 1)
  call h5_truncate(file, 'series/position', 2)
  call h5_truncate(file, 'series/count', 2)         ! as many as stored: unchanged
  call h5_delete(file, 'deep/a/b')                  ! a group with its dataset
  call h5_delete(file, 'spectra/never_written')     ! absent: nothing to do
  call h5_close(file)
  call h5_open(file, path, writable=.false.)
  call h5_read_array(file, 'series/time', reals)
  call check(size(reals) == 1 .and. all(reals == [0.5_wp]), 'truncate_1d_keeps_first_rows')
  call h5_read_array(file, 'series/position', table)
  call check(all(shape(table) == [3, 2]) .and. all(table == reshape([1.0_wp, 2.0_wp, 3.0_wp, 4.0_wp, 5.0_wp, 6.0_wp], &
             [3, 2])), 'truncate_2d_keeps_first_rows')
  call h5_read_array(file, 'series/count', ints)
  call check(all(ints == [1, 2]), 'truncate_to_stored_rows_is_no_change')
  call check(.not. h5_exists(file, 'deep/a/b/reals') .and. .not. h5_exists(file, 'deep/a/b') .and. &
             h5_exists(file, 'deep/a/ints'), 'delete_removes_only_the_named_group')
  call h5_close(file)
  call h5_open(file, path, writable=.true.)
  call h5_append(file, 'series/time', [2.5_wp])
  call h5_append(file, 'series/position', reshape([10.0_wp, 11.0_wp, 12.0_wp], [3, 1]))
  call h5_truncate(file, 'series/count', 0)
  call h5_append(file, 'series/count', [5])
  call h5_close(file)
  call h5_open(file, path, writable=.false.)
  call h5_read_array(file, 'series/time', reals)
  call check(size(reals) == 2 .and. all(reals == [0.5_wp, 2.5_wp]), 'append_after_truncate_1d')
  call h5_read_array(file, 'series/position', table)
  call check(all(shape(table) == [3, 3]) .and. all(table(:, 2) == [4.0_wp, 5.0_wp, 6.0_wp]) .and. &
             all(table(:, 3) == [10.0_wp, 11.0_wp, 12.0_wp]), 'append_after_truncate_2d')
  call h5_read_array(file, 'series/count', ints)
  call check(size(ints) == 1 .and. all(ints == [5]), 'truncate_to_zero_then_append')
  call h5_close(file)

  ! Serial file: rank 0 alone creates, writes and reads it (the particle writers' mode).
  if (is_root()) then
    call h5_create(file, serial_path, serial=.true.)
    call h5_append(file, 'time', [2.0_wp, 3.0_wp])
    call h5_write_array(file, 'seed', 11_i8)
    call h5_write_string(file, 'shape', 'disk')
    call h5_close(file)
    call h5_open(file, serial_path, writable=.false., serial=.true.)
    call h5_read_array(file, 'time', reals)
    call h5_read_string(file, 'shape', text)
    call h5_read_scalar(file, 'seed', long)
    call h5_close(file)
    same = all(reals == [2.0_wp, 3.0_wp]) .and. text == 'disk' .and. long == 11_i8
    call delete_file(serial_path)
  end if
  call check(same .or. .not. is_root(), 'serial_file_on_rank_0')
  call barrier()
  if (is_root()) call delete_file(path)

  call h5_finalize()
  call test_finish()
end program test_hdf5_io
