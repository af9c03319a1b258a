!> Check for the immersed-geometry tests on any rank count: the classification that reuses its
!> work arrays and node lists from call to call (what a moving body gets every step) against a
!> classification into a fresh geometry (nothing kept), over a sequence of random placements of a
!> needle and a disk (random centres, one placement in three near contact so that the image-point
!> fallback is taken; random orientations; the body count and the image-point option changing now
!> and then, which resizes the kept arrays).
module reclassification_check
  use agglo_kinds, only: wp
  use random_stream, only: random_stream_t, stream_uniform, stream_normal
  use quaternion, only: random_orientation
  use spheroid, only: make_spheroid
  use fluid_grid, only: fluid_grid_t
  use immersed_geometry, only: immersed_body_t, immersed_options_t, immersed_geometry_t, component_nodes_t, &
                               classify_nodes
  implicit none
  private
  public :: reclassification_result_t, compare_reclassifications

  !> What the comparison found (over all placements and components on this rank).
  type :: reclassification_result_t
    integer :: placements = 0
    integer :: integer_mismatches = 0     !< counts, statuses, node lists, stencil indices and flags
    real(wp) :: worst_real = 0.0_wp       !< largest |difference| of a record's real field, in cells
    integer :: ghosts = 0                 !< ghost records compared
    integer :: fallbacks = 0              !< of which with the image-point fallback
  end type reclassification_result_t

contains

  subroutine compare_reclassifications(grid, stream, placements, result)
    type(fluid_grid_t), intent(in) :: grid
    type(random_stream_t), intent(inout) :: stream
    integer, intent(in) :: placements
    type(reclassification_result_t), intent(out) :: result
    type(immersed_geometry_t) :: reused
    type(immersed_body_t) :: bodies(2)
    type(immersed_options_t) :: options
    real(wp) :: box(3), direction(3)
    integer :: p, n_bodies, c

    box = [grid%lx, grid%ly, grid%lz]
    bodies(1)%shape = make_spheroid('needle', 3.0_wp * grid%dx, 1.0_wp, 3.0_wp)
    bodies(2)%shape = make_spheroid('disk', 3.5_wp * grid%dx, 1.0_wp, 2.0_wp)
    do p = 1, placements
      n_bodies = merge(1, 2, mod(p, 7) == 0)
      options%image_point = merge('image ', 'mirror', mod(p, 5) == 0)
      bodies(1)%centre = box * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
      bodies(1)%orientation = random_orientation(stream)
      bodies(2)%orientation = random_orientation(stream)
      direction = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
      direction = direction / norm2(direction)
      if (mod(p, 3) == 0) then
        ! Near contact: the disk's centre just beyond the needle's and its own largest half-extent.
        bodies(2)%centre = bodies(1)%centre + direction * (bodies(1)%shape%a + bodies(2)%shape%b) * 0.75_wp
      else
        bodies(2)%centre = box * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
      end if
      bodies(2)%centre = modulo(bodies(2)%centre, box)
      call classify_nodes(grid, bodies(1:n_bodies), options, reused)
      block
        type(immersed_geometry_t) :: fresh
        call classify_nodes(grid, bodies(1:n_bodies), options, fresh)
        do c = 1, 3
          call compare_component(grid, reused%component(c), fresh%component(c), result)
        end do
      end block
      result%placements = result%placements + 1
    end do
  end subroutine compare_reclassifications

  subroutine compare_component(grid, a, b, result)
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(in) :: a, b
    type(reclassification_result_t), intent(inout) :: result
    integer :: g, c
    real(wp) :: h
    h = max(grid%dx, grid%dy, grid%dz)
    call differ(a%n_ghost /= b%n_ghost .or. a%n_interior /= b%n_interior .or. a%n_fallback /= b%n_fallback .or. &
                a%n_overlap /= b%n_overlap .or. a%halo_planes_needed /= b%halo_planes_needed)
    call differ(any(shape(a%status) /= shape(b%status)))
    if (result%integer_mismatches > 0) return
    result%integer_mismatches = result%integer_mismatches + count(a%status /= b%status)
    do g = 1, a%n_interior
      call differ(any(a%interior(:, g) /= b%interior(:, g)) .or. a%interior_body(g) /= b%interior_body(g))
    end do
    do g = 1, a%n_ghost
      associate (x => a%ghost(g), y => b%ghost(g))
        call differ(any(x%node /= y%node) .or. x%body /= y%body .or. (x%fallback .neqv. y%fallback) .or. &
                    any(x%lower_offset /= y%lower_offset) .or. any(x%stencil /= y%stencil) .or. &
                    any(x%stencil_status /= y%stencil_status) .or. any(x%stencil_local .neqv. y%stencil_local) .or. &
                    any(x%stencil_ghost /= y%stencil_ghost) .or. x%self_corner /= y%self_corner)
        ! Lengths in cells; kappa and the weights are already of order one.
        result%worst_real = max(result%worst_real, maxval(abs(x%position - y%position)) / h, &
            maxval(abs(x%surface_point - y%surface_point)) / h, maxval(abs(x%normal - y%normal)), &
            abs(x%distance - y%distance) / h, maxval(abs(x%image_point - y%image_point)) / h, &
            abs(x%image_distance - y%image_distance) / h, abs(x%extrapolation - y%extrapolation), &
            maxval(abs(x%weight - y%weight)))
        if (x%fallback) result%fallbacks = result%fallbacks + 1
      end associate
    end do
    result%ghosts = result%ghosts + a%n_ghost
    ! The component numbers agree too.
    c = a%component - b%component
    call differ(c /= 0)
  contains
    subroutine differ(condition)
      logical, intent(in) :: condition
      if (condition) result%integer_mismatches = result%integer_mismatches + 1
    end subroutine differ
  end subroutine compare_component
end module reclassification_check
