!> Named wall-clock timers: any part of the code registers its own with one call and times a
!> section with tic/toc (or adds a duration it measured itself); at the end the per-step breakdown,
!> min / mean / max over the ranks of each timer, goes to the log (or to a benchmark's output).
!>
!> Registration is by name and idempotent: timer_register('Poisson/projection') returns the same
!> handle every time, so a module can register in its create routine, however often that runs.
!> Every rank must register the same timers in the same order (they do when every rank runs the
!> same code path, which is how the solver works); the reduction checks the count.
!> Hot loops use the integer handle; timer_tic/timer_toc by name are for code run once per step.
!> The clock is replaceable (timer_set_clock) so tests can feed known durations.
module timer_registry
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM, MPI_MIN, MPI_MAX, MPI_DOUBLE_PRECISION, MPI_INTEGER, &
                     MPI_COMM_WORLD, MPI_Comm_size, MPI_Initialized
  use agglo_kinds, only: wp, i8
  use wall_clock, only: wall_time
  use error_handling, only: fatal
  use text_format, only: int_text
  implicit none
  private
  public :: timer_register, timer_tic, timer_toc, timer_add, timer_seconds, timer_count, timer_name, &
            timer_reset_all, timer_set_clock, timer_reduce, timer_breakdown, clock_function, timer_name_length

  integer, parameter :: timer_name_length = 24

  !> A clock: seconds since an arbitrary fixed origin.
  abstract interface
    function clock_function() result(seconds)
      import :: wp
      real(wp) :: seconds
    end function clock_function
  end interface

  type :: timer_t
    character(len=timer_name_length) :: name = ''
    real(wp) :: seconds = 0          !< accumulated on this rank
    real(wp) :: started = 0          !< clock reading at the last tic
    logical :: running = .false.
    integer(i8) :: calls = 0         !< completed tic/toc pairs and timer_add calls
  end type timer_t

  type(timer_t), allocatable :: timers(:)
  integer :: registered = 0
  procedure(clock_function), pointer :: clock => wall_time

contains

  !> The handle of the timer called name, registering it (at zero) if it is new. Names longer
  !> than timer_name_length characters are an error (two timers must never share a truncated name).
  integer function timer_register(name) result(handle)
    character(len=*), intent(in) :: name
    type(timer_t), allocatable :: grown(:)
    if (len_trim(name) > timer_name_length .or. len_trim(name) == 0) call fatal('timer_register: the name '''// &
        trim(name)//''' must have 1 to '//int_text(timer_name_length)//' characters', collective=.false.)
    do handle = 1, registered
      if (timers(handle)%name == name) return
    end do
    if (.not. allocated(timers)) allocate(timers(16))
    if (registered == size(timers)) then
      allocate(grown(2 * size(timers)))
      grown(1:registered) = timers(1:registered)
      call move_alloc(grown, timers)
    end if
    registered = registered + 1
    handle = registered
    timers(handle) = timer_t(name=name)
  end function timer_register

  !> Start the timer (by handle or by name; a name not yet registered is registered).
  subroutine timer_tic(timer)
    class(*), intent(in) :: timer
    integer :: handle
    handle = handle_of(timer)
    timers(handle)%started = clock()
    timers(handle)%running = .true.
  end subroutine timer_tic

  !> Stop the timer and add the time since its tic.
  subroutine timer_toc(timer)
    class(*), intent(in) :: timer
    integer :: handle
    handle = handle_of(timer)
    if (.not. timers(handle)%running) call fatal('timer_toc: timer '''//trim(timers(handle)%name)// &
        ''' was not started', collective=.false.)
    call timer_add(handle, clock() - timers(handle)%started)
    timers(handle)%running = .false.
  end subroutine timer_toc

  !> Add seconds measured by the caller (for sections timed as a difference of other readings).
  subroutine timer_add(handle, seconds)
    integer, intent(in) :: handle
    real(wp), intent(in) :: seconds
    timers(handle)%seconds = timers(handle)%seconds + seconds
    timers(handle)%calls = timers(handle)%calls + 1
  end subroutine timer_add

  !> Seconds accumulated on this rank.
  real(wp) function timer_seconds(handle)
    integer, intent(in) :: handle
    timer_seconds = timers(handle)%seconds
  end function timer_seconds

  integer function timer_count()
    timer_count = registered
  end function timer_count

  function timer_name(handle) result(name)
    integer, intent(in) :: handle
    character(len=:), allocatable :: name
    name = trim(timers(handle)%name)
  end function timer_name

  !> Every timer back to zero (the registrations stay).
  subroutine timer_reset_all()
    integer :: handle
    do handle = 1, registered
      timers(handle) = timer_t(name=timers(handle)%name)
    end do
  end subroutine timer_reset_all

  !> Use another clock (tests: a clock returning known readings); no argument: the wall clock.
  subroutine timer_set_clock(new_clock)
    procedure(clock_function), optional :: new_clock
    if (present(new_clock)) then
      clock => new_clock
    else
      clock => wall_time
    end if
  end subroutine timer_set_clock

  !> Seconds of every timer divided by divisor (e.g. the number of steps), reduced over the ranks:
  !> smallest, mean and largest (each of size timer_count()). Collective.
  subroutine timer_reduce(divisor, smallest, mean, largest)
    real(wp), intent(in) :: divisor
    real(wp), allocatable, intent(out) :: smallest(:), mean(:), largest(:)
    integer :: counts(2)
    logical :: mpi_up
    call MPI_Initialized(mpi_up)
    if (mpi_up) then
      counts = [registered, -registered]
      call MPI_Allreduce(MPI_IN_PLACE, counts, 2, MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD)
      if (counts(1) /= -counts(2)) call fatal('timer_reduce: the ranks registered different timers')
    end if
    call min_mean_max(timers(1:registered)%seconds / divisor, smallest, mean, largest)
  end subroutine timer_reduce

  !> The per-step breakdown as text lines: a heading, then per timer that ran "name min mean max"
  !> in ms per step, and a last line for the whole step (total_seconds, measured by the caller:
  !> it includes whatever no timer covers). Collective; every rank gets the lines.
  function timer_breakdown(steps, total_seconds) result(lines)
    integer(i8), intent(in) :: steps
    real(wp), intent(in) :: total_seconds
    character(len=80), allocatable :: lines(:)
    real(wp), allocatable :: smallest(:), mean(:), largest(:), whole_min(:), whole_mean(:), whole_max(:)
    real(wp) :: per_step
    integer :: handle, n
    per_step = 1.0e3_wp / real(max(steps, 1_i8), wp)    ! ms per step from seconds
    call timer_reduce(1.0_wp, smallest, mean, largest)
    call min_mean_max([total_seconds], whole_min, whole_mean, whole_max)
    allocate(lines(count(timers(1:registered)%calls > 0) + 2))
    lines(1) = 'timing per step (ms; min / mean / max over ranks):'
    n = 1
    do handle = 1, registered
      if (timers(handle)%calls == 0) cycle
      n = n + 1
      write(lines(n), '(2x,a24,3f10.3)') timers(handle)%name, per_step * smallest(handle), &
          per_step * mean(handle), per_step * largest(handle)
    end do
    write(lines(n + 1), '(2x,a24,3f10.3)') 'whole step (incl. other)', per_step * whole_min(1), &
        per_step * whole_mean(1), per_step * whole_max(1)
  end function timer_breakdown

  !> Element-wise minimum, mean and maximum of values over the ranks (collective; without MPI,
  !> all three are the values).
  subroutine min_mean_max(values, smallest, mean, largest)
    real(wp), intent(in) :: values(:)
    real(wp), allocatable, intent(out) :: smallest(:), mean(:), largest(:)
    integer :: ranks
    logical :: mpi_up
    smallest = values; mean = values; largest = values
    call MPI_Initialized(mpi_up)
    if (.not. mpi_up) return
    call MPI_Comm_size(MPI_COMM_WORLD, ranks)
    call MPI_Allreduce(MPI_IN_PLACE, smallest, size(values), MPI_DOUBLE_PRECISION, MPI_MIN, MPI_COMM_WORLD)
    call MPI_Allreduce(MPI_IN_PLACE, mean, size(values), MPI_DOUBLE_PRECISION, MPI_SUM, MPI_COMM_WORLD)
    call MPI_Allreduce(MPI_IN_PLACE, largest, size(values), MPI_DOUBLE_PRECISION, MPI_MAX, MPI_COMM_WORLD)
    mean = mean / ranks
  end subroutine min_mean_max

  !> The handle of an integer handle or of a name (registered if new).
  integer function handle_of(timer) result(handle)
    class(*), intent(in) :: timer
    select type (timer)
    type is (integer)
      if (timer < 1 .or. timer > registered) call fatal('timer: no timer with handle '//int_text(timer), &
          collective=.false.)
      handle = timer
    type is (character(len=*))
      handle = timer_register(timer)
    class default
      handle = 0
      call fatal('timer: a timer is named by its integer handle or its name', collective=.false.)
    end select
  end function handle_of
end module timer_registry
