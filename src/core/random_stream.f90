!> Reproducible random streams: xoshiro256** (Blackman & Vigna 2018) seeded by splitmix64,
!> normals by the Box-Muller transform (the paper's choice). The whole state is the public
!> components of random_stream_t, so a checkpoint stores it and a restart continues bit for bit.
!> Integer arithmetic relies on two's-complement wrap-around (compiled with -fwrapv).
module random_stream
  use agglo_kinds, only: wp, i8
  use physical_constants, only: two_pi
  implicit none
  private
  public :: random_stream_t, stream_seed, stream_uniform, stream_normal, stream_state_size, &
            stream_pack, stream_unpack

  type :: random_stream_t
    integer(i8) :: s(4) = 0_i8
    logical :: has_spare = .false.     !< Box-Muller makes normals in pairs
    real(wp) :: spare = 0.0_wp
  end type random_stream_t

  integer, parameter :: stream_state_size = 6   !< int64 words in a packed state

contains

  !> Seed a stream from a deck seed and a stream number (independent streams per purpose).
  subroutine stream_seed(stream, seed, stream_id)
    type(random_stream_t), intent(out) :: stream
    integer(i8), intent(in) :: seed
    integer, intent(in), optional :: stream_id
    integer(i8) :: x
    integer :: i
    x = seed
    if (present(stream_id)) x = ieor(x, splitmix_next_value(int(stream_id, i8) + 7919_i8))
    do i = 1, 4
      stream%s(i) = splitmix_next(x)
    end do
    if (all(stream%s == 0_i8)) stream%s(1) = 1_i8
    stream%has_spare = .false.
    stream%spare = 0.0_wp
  end subroutine stream_seed

  !> splitmix64 step (Steele, Lea & Flood 2014); advances x.
  function splitmix_next(x) result(z)
    integer(i8), intent(inout) :: x
    integer(i8) :: z
    x = x - 7046029254386353131_i8          ! + 0x9E3779B97F4A7C15
    z = splitmix_next_value(x)
  end function splitmix_next

  pure function splitmix_next_value(x0) result(z)
    integer(i8), intent(in) :: x0
    integer(i8) :: z
    z = x0
    z = ieor(z, ishft(z, -30)) * (-4658895280553007687_i8)   ! 0xBF58476D1CE4E5B9
    z = ieor(z, ishft(z, -27)) * (-7723592293110705685_i8)   ! 0x94D049BB133111EB
    z = ieor(z, ishft(z, -31))
  end function splitmix_next_value

  function next_bits(stream) result(r)
    type(random_stream_t), intent(inout) :: stream
    integer(i8) :: r, t
    r = ishftc(stream%s(2) * 5_i8, 7) * 9_i8
    t = ishft(stream%s(2), 17)
    stream%s(3) = ieor(stream%s(3), stream%s(1))
    stream%s(4) = ieor(stream%s(4), stream%s(2))
    stream%s(2) = ieor(stream%s(2), stream%s(3))
    stream%s(1) = ieor(stream%s(1), stream%s(4))
    stream%s(3) = ieor(stream%s(3), t)
    stream%s(4) = ishftc(stream%s(4), 45)
  end function next_bits

  !> Uniform deviate in [0, 1) with 53 random bits.
  function stream_uniform(stream) result(u)
    type(random_stream_t), intent(inout) :: stream
    real(wp) :: u
    u = real(ishft(next_bits(stream), -11), wp) * 2.0_wp**(-53)
  end function stream_uniform

  !> Standard normal deviate (Box-Muller, both values of a pair used).
  function stream_normal(stream) result(g)
    type(random_stream_t), intent(inout) :: stream
    real(wp) :: g, u1, u2, radius
    if (stream%has_spare) then
      stream%has_spare = .false.
      g = stream%spare
      return
    end if
    u1 = 1.0_wp - stream_uniform(stream)     ! in (0, 1]: log is finite
    u2 = stream_uniform(stream)
    radius = sqrt(-2.0_wp * log(u1))
    g = radius * cos(two_pi * u2)
    stream%spare = radius * sin(two_pi * u2)
    stream%has_spare = .true.
  end function stream_normal

  !> Pack the full state into int64 words (for checkpoints); exact, including the spare normal.
  pure function stream_pack(stream) result(words)
    type(random_stream_t), intent(in) :: stream
    integer(i8) :: words(stream_state_size)
    words(1:4) = stream%s
    words(5) = merge(1_i8, 0_i8, stream%has_spare)
    words(6) = transfer(stream%spare, 0_i8)
  end function stream_pack

  pure function stream_unpack(words) result(stream)
    integer(i8), intent(in) :: words(stream_state_size)
    type(random_stream_t) :: stream
    stream%s = words(1:4)
    stream%has_spare = (words(5) /= 0_i8)
    stream%spare = transfer(words(6), 0.0_wp)
  end function stream_unpack
end module random_stream
