!> Wall-clock readings (the progress line, the timer registry) and durations as text.
module wall_clock
  use agglo_kinds, only: wp, i8
  implicit none
  private
  public :: wall_time, format_duration

contains

  !> Seconds since an arbitrary fixed origin.
  function wall_time() result(seconds)
    real(wp) :: seconds
    integer(i8) :: count, rate
    call system_clock(count, rate)
    seconds = real(count, wp) / real(rate, wp)
  end function wall_time

  !> "1h02m03s", "4m05s" or "6.1s".
  function format_duration(seconds) result(text)
    real(wp), intent(in) :: seconds
    character(len=16) :: text
    integer :: h, m, s
    if (seconds < 60.0_wp) then
      write(text, '(f4.1,a)') max(seconds, 0.0_wp), 's'
      text = adjustl(text)
    else
      s = nint(seconds)
      h = s / 3600
      m = (s - 3600 * h) / 60
      s = s - 3600 * h - 60 * m
      if (h > 0) then
        write(text, '(i0,a,i2.2,a,i2.2,a)') h, 'h', m, 'm', s, 's'
      else
        write(text, '(i0,a,i2.2,a)') m, 'm', s, 's'
      end if
    end if
  end function format_duration
end module wall_clock
