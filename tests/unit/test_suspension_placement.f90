! checks: 10
!> Unit tests of suspension_placement (random sequential addition in a periodic box):
!>  - 300 needles (aspect 5) at 10% by volume and a mix of 100 disks, 100 needles and 100 spheres
!>    at 12%: every body placed, the volume fraction the one requested (the sum of the body volumes
!>    over the box volume, to 1e-12), and every pair's exact surface gap (module closest_points at
!>    the minimum image, over every pair i < j, brute force) at least min_gap, with some pairs near
!>    enough to need the exact gap (the bounding spheres alone would not have placed them);
!>  - the same stream seed places the same bodies (stored values compared exactly);
!>  - the placement's orientations are uniform: the mean of the symmetry axis' components and of
!>    their squares over 20000 draws within 4 standard errors of 0 and 1/3 (isotropy);
!>  - random_relative_velocities: no net momentum (to round-off) and the rms of the components
!>    within 5% of the one asked for (2000 bodies: standard error about 1%);
!>  - spheres at 45% by volume are refused (random sequential addition of spheres jams at 0.38,
!>    Feder 1980, Torquato, Uche & Stillinger 2006): the placement stops incomplete below 0.40.
program test_suspension_placement
  use agglo_kinds, only: wp, i8
  use random_stream, only: random_stream_t, stream_seed
  use spheroid, only: spheroid_t, make_spheroid
  use quaternion, only: rotate_to_lab, random_orientation
  use closest_points, only: closest_points_t, find_closest_points
  use periodic_box, only: image_shift
  use suspension_placement, only: placement_t, place_bodies, random_relative_velocities
  use test_framework, only: test_start, test_finish, check
  implicit none
  real(wp), parameter :: r = 50.0e-6_wp, density = 2710.0_wp, gap = 2.0e-6_wp
  type(spheroid_t), allocatable :: shapes(:)
  type(placement_t) :: placement, again
  type(random_stream_t) :: stream
  real(wp) :: box(3), axis(3), mean(3), mean_square(3), velocities(3, 2000), masses(2000)
  integer :: i, n

  call test_start('suspension_placement')

  ! 300 needles at 10%: the box volume from the fraction.
  allocate(shapes(300))
  shapes = make_spheroid('needle', r, density, 5.0_wp)
  box = (300 * shapes(1)%volume / 0.10_wp)**(1.0_wp / 3.0_wp)
  call stream_seed(stream, 7_i8, 4)
  call place_bodies(shapes, box, gap, 10000, stream, placement)
  call check(placement%complete .and. placement%placed == 300 .and. &
             abs(placement%volume_fraction - 0.10_wp) < 1.0e-12_wp, 'needles_10_percent_placed')
  call check_gaps('needles_all_gaps_at_least_min_gap')
  call stream_seed(stream, 7_i8, 4)
  call place_bodies(shapes, box, gap, 10000, stream, again)
  call check(all(again%centres == placement%centres) .and. all(again%quaternions == placement%quaternions), &
             'same_seed_same_placement')

  ! A mix at 12%.
  deallocate(shapes)
  allocate(shapes(300))
  shapes(1:100) = make_spheroid('disk', r, density, 5.0_wp)
  shapes(101:200) = make_spheroid('needle', r, density, 5.0_wp)
  shapes(201:300) = make_spheroid('sphere', r, density)
  box = (sum(shapes%volume) / 0.12_wp)**(1.0_wp / 3.0_wp)
  call stream_seed(stream, 11_i8, 4)
  call place_bodies(shapes, box, gap, 10000, stream, placement)
  call check(placement%complete .and. abs(placement%volume_fraction - 0.12_wp) < 1.0e-12_wp, 'mixed_12_percent_placed')
  call check_gaps('mixed_all_gaps_at_least_min_gap')

  ! Uniform orientations: the symmetry axis (body x in the lab frame).
  call stream_seed(stream, 3_i8, 4)
  mean = 0
  mean_square = 0
  n = 20000
  do i = 1, n
    axis = rotate_to_lab(random_orientation(stream), [1.0_wp, 0.0_wp, 0.0_wp])
    mean = mean + axis / n
    mean_square = mean_square + axis**2 / n
  end do
  ! Standard errors: sqrt(1/3 / n) for the mean, sqrt(4/45 / n) for the mean square (uniform on the sphere).
  call check(all(abs(mean) < 4.0_wp * sqrt(1.0_wp / 3.0_wp / n)) .and. &
             all(abs(mean_square - 1.0_wp / 3.0_wp) < 4.0_wp * sqrt(4.0_wp / 45.0_wp / n)), 'uniform_orientations')

  ! Random relative velocities.
  do i = 1, size(masses)
    masses(i) = 1.0_wp + mod(i, 3)
  end do
  call stream_seed(stream, 5_i8, 4)
  velocities = random_relative_velocities(stream, masses, 2.0e-3_wp)
  call check(all(abs(matmul(velocities, masses)) < 1.0e-12_wp * 2.0e-3_wp * sum(masses)), 'no_net_momentum')
  call check(abs(sqrt(sum(velocities**2) / size(velocities)) / 2.0e-3_wp - 1.0_wp) < 0.05_wp, 'velocity_rms')

  ! Spheres at 45%: beyond the jamming limit of random sequential addition.
  deallocate(shapes)
  allocate(shapes(200))
  shapes = make_spheroid('sphere', r, density)
  box = (sum(shapes%volume) / 0.45_wp)**(1.0_wp / 3.0_wp)
  call stream_seed(stream, 13_i8, 4)
  call place_bodies(shapes, box, gap, 2000, stream, placement)
  call check(.not. placement%complete .and. placement%placed < 200, 'spheres_45_percent_incomplete')
  call check(placement%volume_fraction < 0.40_wp .and. placement%volume_fraction > 0.2_wp, &
             'spheres_45_percent_stops_below_jamming')
  call test_finish()

contains

  !> Every pair's exact gap at the minimum image >= min_gap (brute force over all pairs); some
  !> pairs' bounding spheres within min_gap (so the exact gap decided).
  subroutine check_gaps(name)
    character(len=*), intent(in) :: name
    type(closest_points_t) :: contact
    real(wp) :: image(3), smallest
    integer :: i, j, near
    logical :: ok
    ok = .true.
    near = 0
    smallest = huge(1.0_wp)
    do i = 1, size(shapes) - 1
      do j = i + 1, size(shapes)
        associate (x => placement%centres)
          image = x(:, j) + image_shift(x(:, j) - x(:, i), box)
          if (norm2(image - x(:, i)) - max(shapes(i)%a, shapes(i)%b) - max(shapes(j)%a, shapes(j)%b) > gap) cycle
          near = near + 1
          call find_closest_points(shapes(i), x(:, i), placement%quaternions(:, i), shapes(j), image, &
                                   placement%quaternions(:, j), contact)
          ok = ok .and. contact%converged .and. contact%gap >= gap * (1.0_wp - 1.0e-9_wp)
          smallest = min(smallest, contact%gap)
        end associate
      end do
    end do
    print '(a,i0,a,es10.3,a)', '  ', near, ' pairs with bounding spheres within min_gap; smallest exact gap ', &
      smallest, ' m'
    call check(ok .and. near > 0, name)
  end subroutine check_gaps
end program test_suspension_placement
