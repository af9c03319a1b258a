!> The paper's pair set-up (docs/design.md, "The paper's simulation protocol"): two spheroids of the same
!> shape with uniformly random (or given) orientations, placed so that their surface gap along the
!> closest-approach vector is exactly the deck's gap, each moving towards the other along that
!> vector at half the relative speed.
module pair_setup
  use agglo_kinds, only: wp, i8
  use config_pair, only: pair_config_t
  use error_handling, only: fatal
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: random_orientation, quaternion_from_axis_angle
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid
  use closest_points, only: closest_points_t, find_closest_points
  implicit none
  private
  public :: pair_t, build_pair

  !> Random stream id of the particle set-up (ids: 1 fluid initial field, 2 forcing, 3 particles).
  integer, parameter :: particle_stream_id = 3
  integer, parameter :: max_placement_iterations = 20

  type :: pair_t
    type(spheroid_t) :: shape                 !< both particles have this shape
    type(rigid_body_t) :: body(2)
    type(closest_points_t) :: contact         !< closest points of the placed pair
  end type pair_t

contains

  !> Build the pair from &pair and the run seed. The gap is exact to 1e-12 of the radius.
  !> box: the periodic box of a resolved fluid (m), where centre = 'random' draws the centre
  !> (absent: the cube of &pair box_length).
  subroutine build_pair(cfg, seed, pair, box)
    type(pair_config_t), intent(in) :: cfg
    integer, intent(in) :: seed
    type(pair_t), intent(out) :: pair
    real(wp), intent(in), optional :: box(3)
    type(random_stream_t) :: stream
    real(wp) :: orientation(4, 2), direction(3), centre(3), reach, shift, normal(3)
    integer :: i, iteration

    call stream_seed(stream, int(seed, i8), particle_stream_id)
    if (cfg%shape == 'sphere') then
      pair%shape = make_spheroid('sphere', cfg%radius, cfg%density)
    else
      pair%shape = make_spheroid(cfg%shape, cfg%radius, cfg%density, cfg%aspect_ratio)
    end if

    ! Draws in a fixed order (orientations, direction, centre), so a deck's seed fixes the scene.
    if (cfg%orientation == 'random') then
      orientation(:, 1) = random_orientation(stream)
      orientation(:, 2) = random_orientation(stream)
    else
      orientation(:, 1) = quaternion_from_axis_angle(cfg%axis1, cfg%angle1)
      orientation(:, 2) = quaternion_from_axis_angle(cfg%axis2, cfg%angle2)
    end if
    if (cfg%approach == 'random') then
      direction = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    else
      direction = cfg%approach_direction
    end if
    direction = direction / norm2(direction)
    if (cfg%centre == 'random') then
      centre = [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
      if (present(box)) then
        centre = box * centre
      else
        centre = cfg%box_length * centre
      end if
    else
      centre = cfg%centre_position
    end if

    ! Start clear of each other along the drawn direction, then slide particle 2 along the common
    ! normal: a translation along it keeps the closest points a common-normal pair, so the gap
    ! changes by exactly the shift (a second pass only mops up round-off).
    reach = max(pair%shape%a, pair%shape%b)
    do i = 1, 2
      call rigid_body_of_spheroid(pair%body(i), pair%shape, centre + (i - 1.5_wp) * (2.0_wp * reach + cfg%gap) &
                                  * direction, orientation(:, i))
    end do
    do iteration = 1, max_placement_iterations
      call find_closest_points(pair%shape, pair%body(1)%position, pair%body(1)%quaternion, pair%shape, &
                               pair%body(2)%position, pair%body(2)%quaternion, pair%contact)
      if (.not. pair%contact%converged) call fatal('pair set-up: closest points did not converge: '// &
                                                   trim(pair%contact%message))
      shift = cfg%gap - pair%contact%gap
      if (abs(shift) <= 1.0e-12_wp * cfg%radius) exit
      pair%body(1)%position = pair%body(1)%position - 0.5_wp * shift * pair%contact%normal
      pair%body(2)%position = pair%body(2)%position + 0.5_wp * shift * pair%contact%normal
    end do
    if (abs(shift) > 1.0e-12_wp * cfg%radius) call fatal('pair set-up: could not place the pair at the requested gap')

    ! Each particle moves towards the other along the closest-approach vector at v/2.
    normal = pair%contact%normal
    pair%body(1)%velocity = 0.5_wp * cfg%relative_speed * normal
    pair%body(2)%velocity = -0.5_wp * cfg%relative_speed * normal
  end subroutine build_pair
end module pair_setup
