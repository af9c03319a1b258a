!> Kind parameters used everywhere in Agglo.
module agglo_kinds
  use, intrinsic :: iso_fortran_env, only: real64, int32, int64
  implicit none
  private
  public :: wp, ip, i8

  integer, parameter :: wp = real64   !< working precision for all reals
  integer, parameter :: ip = int32    !< default integer
  integer, parameter :: i8 = int64    !< 64-bit integers (step counters, random state)
end module agglo_kinds
