! checks: 7
!> Unit tests of random_stream: reproducibility, restart of the stream, moments of the deviates.
program test_random_stream
  use agglo_kinds, only: wp, i8
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal, stream_pack, &
                           stream_unpack, stream_state_size
  use test_framework, only: test_start, test_finish, check, check_close
  implicit none
  type(random_stream_t) :: a, b, c
  integer(i8) :: words(stream_state_size)
  integer, parameter :: n = 400000
  real(wp) :: x, sum1, sum2, sum4, u_mean
  integer :: i
  logical :: same

  call test_start('random_stream')

  call stream_seed(a, 42_i8)
  call stream_seed(b, 42_i8)
  same = .true.
  do i = 1, 1000
    same = same .and. (stream_normal(a) == stream_normal(b))
  end do
  call check(same, 'same_seed_same_sequence')

  call stream_seed(c, 42_i8, stream_id=1)
  call check(stream_uniform(c) /= stream_uniform(a), 'stream_ids_differ')

  ! Pack mid-pair (a spare normal is cached) and continue from the unpacked copy: bit for bit.
  x = stream_normal(a)
  words = stream_pack(a)
  b = stream_unpack(words)
  same = .true.
  do i = 1, 1001
    same = same .and. (stream_normal(a) == stream_normal(b))
  end do
  call check(same, 'pack_unpack_continues_bit_for_bit')

  ! Moments of N(0,1) over n samples: standard errors sqrt(1/n), sqrt(2/n), sqrt(96/n).
  call stream_seed(a, 7_i8)
  sum1 = 0; sum2 = 0; sum4 = 0; u_mean = 0
  do i = 1, n
    x = stream_normal(a)
    sum1 = sum1 + x; sum2 = sum2 + x**2; sum4 = sum4 + x**4
    u_mean = u_mean + stream_uniform(a)
  end do
  call check_close(sum1 / n, 0.0_wp, 0.0_wp, 'normal_mean', abs_tol=4 * sqrt(1.0_wp / n))
  call check_close(sum2 / n, 1.0_wp, 0.0_wp, 'normal_variance', abs_tol=4 * sqrt(2.0_wp / n))
  call check_close(sum4 / n, 3.0_wp, 0.0_wp, 'normal_fourth_moment', abs_tol=4 * sqrt(96.0_wp / n))
  call check_close(u_mean / n, 0.5_wp, 0.0_wp, 'uniform_mean', abs_tol=4 * sqrt(1.0_wp / (12.0_wp * n)))

  call test_finish()
end program test_random_stream
