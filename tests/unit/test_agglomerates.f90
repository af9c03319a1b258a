! checks: 52
!> Unit tests of agglomerates and bond_graph (docs/theory.md, "Agglomerates"): clusters of bonded
!> spheroids against analytic references. Spheres of radius r touch at centre distance 2 r.
!>  - Straight chain of n spheres, centres 2 r apart: the centres are n equally spaced points, whose
!>    variance is (2 r)^2 (n^2 - 1) / 12 (the discrete uniform distribution), so
!>    R_g^2 = r^2 (n^2 - 1) / 3 over the centres, plus 3 r^2 / 5 for the spheres' own gyration
!>    (the second moment of a uniform ball about its centre, (1/V) int |x|^2 dV = 3 r^2 / 5).
!>  - Equilateral triangle of side 2 r: centres on the circumcircle of radius 2 r / sqrt(3), so
!>    R_g^2 = 4 r^2 / 3 (+ 3 r^2 / 5); in-plane eigenvalues 2 r^2 / 3, out of plane 0 (+ r^2 / 5 each).
!>  - Regular tetrahedron of edge 2 r: circumradius r sqrt(3/2), so R_g^2 = 3 r^2 / 2 (+ 3 r^2 / 5),
!>    and by its cubic symmetry the gyration tensor is isotropic: three eigenvalues r^2 / 2 (+ r^2 / 5).
!>  - A solid spheroid alone: gyration tensor diag(a^2, b^2, b^2) / 5, R_g^2 = (a^2 + 2 b^2) / 5.
!>  - A fractal fit on exact power-law data returns the exponent and prefactor to round-off.
program test_agglomerates
  use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
  use agglo_kinds, only: wp, i8
  use physical_constants, only: pi
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: random_orientation, rotation_matrix, quaternion_from_axis_angle, quaternion_product, &
                        quaternion_identity
  use vector_algebra, only: symmetric_eigenvalues3
  use sample_statistics, only: linear_fit_t, linear_fit, sorted_values
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid
  use bond_graph, only: component_labels
  use agglomerates, only: bond_t, agglomerates_t, agglomerates_analyse, bond_image, carried_bond_image, &
                          fractal_fit_t, fractal_dimension_fit, cluster_fractal_dimension
  use test_framework, only: test_start, test_finish, check, check_close, check_below, check_equal
  implicit none
  real(wp), parameter :: r = 50.0e-6_wp, density = 2710.0_wp, box = 1.0e-3_wp
  real(wp), parameter :: periodic(3) = [box, box, box], unbounded(3) = 0.0_wp
  type(random_stream_t) :: stream

  call test_start('agglomerates')
  call stream_seed(stream, 33_i8, stream_id=5)
  call straight_chain()
  call single_bodies()
  call chain_across_the_boundary()
  call percolating_clusters()
  call separate_clusters()
  call triangle_across_the_boundary()
  call tetrahedron()
  call unequal_masses()
  call random_graphs()
  call long_chain()
  call needle_angles()
  call fractal_fits()
  call eigenvalues_of_rotated_tensors()
  call test_finish()

contains

  !> n spheres of radius r and the given positions (3, n), random orientations (a sphere's own
  !> gyration tensor is isotropic, so they must not matter).
  subroutine spheres_at(positions, shapes, bodies)
    real(wp), intent(in) :: positions(:,:)
    type(spheroid_t), allocatable, intent(out) :: shapes(:)
    type(rigid_body_t), allocatable, intent(out) :: bodies(:)
    integer :: i
    allocate(shapes(size(positions, 2)), bodies(size(positions, 2)))
    do i = 1, size(positions, 2)
      shapes(i) = make_spheroid('sphere', r, density)
      call rigid_body_of_spheroid(bodies(i), shapes(i), positions(:, i), random_orientation(stream))
    end do
  end subroutine spheres_at

  !> Bonds (pairs(1, b), pairs(2, b)) with the minimum images of the positions.
  function bonds_of(pairs, positions, box_length) result(bonds)
    integer, intent(in) :: pairs(:,:)
    real(wp), intent(in) :: positions(:,:), box_length(3)
    type(bond_t) :: bonds(size(pairs, 2))
    integer :: b
    do b = 1, size(pairs, 2)
      bonds(b)%first = pairs(1, b)
      bonds(b)%second = pairs(2, b)
      bonds(b)%image = bond_image(positions(:, pairs(1, b)), positions(:, pairs(2, b)), box_length)
    end do
  end function bonds_of

  function random_unit_vector() result(e)
    real(wp) :: e(3)
    e = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    e = e / norm2(e)
  end function random_unit_vector

  !> Centres of a straight chain of n touching spheres along e, centred on centre.
  function chain_positions(n, centre, e) result(x)
    integer, intent(in) :: n
    real(wp), intent(in) :: centre(3), e(3)
    real(wp) :: x(3, n)
    integer :: k
    do k = 1, n
      x(:, k) = centre + 2.0_wp * r * (real(k, wp) - 0.5_wp * real(n + 1, wp)) * e
    end do
  end function chain_positions

  function chain_pairs(n) result(pairs)
    integer, intent(in) :: n
    integer :: pairs(2, n - 1), k
    do k = 1, n - 1
      pairs(:, k) = [k, k + 1]
    end do
  end function chain_pairs

  subroutine straight_chain()
    integer, parameter :: n = 7
    real(wp) :: x(3, n), e(3), rg2_centres, expected(3)
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    type(agglomerates_t) :: a
    e = random_unit_vector()
    x = chain_positions(n, 0.5_wp * periodic, e)
    call spheres_at(x, shapes, bodies)
    call agglomerates_analyse(shapes, bodies, periodic, bonds_of(chain_pairs(n), x, periodic), a)
    rg2_centres = r**2 * real(n**2 - 1, wp) / 3.0_wp
    call check_equal(a%clusters, 1, 'chain_is_one_cluster')
    call check_close(a%radius_of_gyration_centres(1)**2, rg2_centres, 1.0e-12_wp, 'chain_rg_centres_r2_n2m1_over_3')
    call check_close(a%radius_of_gyration(1)**2, rg2_centres + 0.6_wp * r**2, 1.0e-12_wp, 'chain_rg_with_sphere_gyration')
    ! Along the chain r^2 (n^2 - 1) / 3, across it 0; r^2 / 5 in every direction from the spheres.
    expected = [0.2_wp * r**2, 0.2_wp * r**2, rg2_centres + 0.2_wp * r**2]
    call check_below(maxval(abs(a%gyration_eigenvalues(:, 1) - expected)) / expected(3), 1.0e-12_wp, &
                     'chain_gyration_eigenvalues')
    call check(all(a%coordination == [1, 2, 2, 2, 2, 2, 1]), 'chain_coordination_ends_1_middle_2')
    call check_close(a%mean_coordination, 2.0_wp * real(n - 1, wp) / real(n, wp), 1.0e-15_wp, 'chain_mean_coordination_2B_over_N')
  end subroutine straight_chain

  subroutine single_bodies()
    type(spheroid_t) :: shapes(2)
    type(rigid_body_t) :: bodies(2)
    type(bond_t) :: none(0)
    type(agglomerates_t) :: a
    real(wp) :: expected(3)
    shapes(1) = make_spheroid('sphere', r, density)
    shapes(2) = make_spheroid('needle', r, density)
    call rigid_body_of_spheroid(bodies(1), shapes(1), 0.3_wp * periodic, random_orientation(stream))
    call rigid_body_of_spheroid(bodies(2), shapes(2), 0.7_wp * periodic, random_orientation(stream))
    call agglomerates_analyse(shapes, bodies, periodic, none, a)
    call check_close(a%radius_of_gyration(1), sqrt(0.6_wp) * r, 1.0e-14_wp, 'single_sphere_rg_sqrt_3_5_r')
    call check_close(a%radius_of_gyration(2)**2, (shapes(2)%a**2 + 2.0_wp * shapes(2)%b**2) / 5.0_wp, 1.0e-14_wp, &
                     'single_needle_rg2_a2_plus_2b2_over_5')
    ! A randomly oriented needle: eigenvalues b^2/5 (twice) and a^2/5, whatever its orientation.
    expected = [shapes(2)%b**2, shapes(2)%b**2, shapes(2)%a**2] / 5.0_wp
    call check_below(maxval(abs(a%gyration_eigenvalues(:, 2) - expected)) / expected(3), 1.0e-14_wp, &
                     'single_needle_eigenvalues_diag_a2_b2_b2_over_5')
    call agglomerates_analyse(shapes, bodies, periodic, none, a, body_extent=.false.)
    call check_below(maxval(a%radius_of_gyration), 1.0e-12_wp * r, 'single_bodies_without_extent_rg_zero')
  end subroutine single_bodies

  !> The chain of straight_chain moved across the x and y boundaries and wrapped: the same R_g,
  !> the centre of mass wrapped, neighbours 2 r apart once unwrapped, no percolation.
  subroutine chain_across_the_boundary()
    integer, parameter :: n = 7
    real(wp) :: x(3, n), wrapped(3, n), e(3), shift(3), centre(3), gap
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    type(bond_t), allocatable :: bonds(:), reversed(:)
    type(agglomerates_t) :: a, b
    integer :: k, moved(3)
    e = random_unit_vector()
    shift = [0.513_wp, 0.47_wp, 0.0_wp] * box   ! the centre near, not on, the x boundary
    x = chain_positions(n, 0.5_wp * periodic + shift, e)
    centre = sum(x, dim=2) / n
    wrapped = modulo(x, box)
    call spheres_at(wrapped, shapes, bodies)
    bonds = bonds_of(chain_pairs(n), wrapped, periodic)
    call check(count([(any(bonds(k)%image /= 0), k = 1, n - 1)]) > 0, 'periodic_chain_crosses_the_boundary')
    call agglomerates_analyse(shapes, bodies, periodic, bonds, a)
    call check_close(a%radius_of_gyration(1)**2, r**2 * real(n**2 - 1, wp) / 3.0_wp + 0.6_wp * r**2, 1.0e-12_wp, &
                     'periodic_chain_same_rg_as_unwrapped')
    call check_below(maxval(abs(a%centre_of_mass(:, 1) - modulo(centre, box))), 1.0e-12_wp * box, &
                     'periodic_chain_centre_of_mass_wrapped')
    gap = 0.0_wp
    do k = 1, n - 1
      gap = max(gap, abs(norm2(a%unwrapped(:, k + 1) - a%unwrapped(:, k)) - 2.0_wp * r))
    end do
    call check_below(gap / r, 1.0e-12_wp, 'periodic_chain_unwrapped_contiguous')
    call check(.not. a%percolating(1) .and. a%percolating_clusters == 0, 'periodic_chain_not_percolating')
    ! The same bonds listed backwards and each from its other end: the same clusters and shape.
    allocate(reversed(n - 1))
    do k = 1, n - 1
      reversed(k) = bond_t(bonds(n - k)%second, bonds(n - k)%first, -bonds(n - k)%image)
    end do
    call agglomerates_analyse(shapes, bodies, periodic, reversed, b)
    call check(all(a%cluster_of == b%cluster_of) .and. &
               abs(a%radius_of_gyration(1) - b%radius_of_gyration(1)) <= 1.0e-14_wp * a%radius_of_gyration(1), &
               'bond_order_and_direction_do_not_matter')
    ! Body 2 crosses the upper x boundary (wrapped back by one period): the carried image is the
    ! minimum image of the moved positions.
    wrapped(1, 2) = wrapped(1, 2) + box
    moved = bond_image(wrapped(:, 1), wrapped(:, 2), periodic)
    wrapped(1, 2) = wrapped(1, 2) - box
    call check(all(carried_bond_image(bonds(1)%image, [0_i8, 0_i8, 0_i8], [-1_i8, 0_i8, 0_i8]) == moved) .and. &
               all(carried_bond_image(moved, [0_i8, 0_i8, 0_i8], [1_i8, 0_i8, 0_i8]) == bonds(1)%image), &
               'carried_bond_image_follows_box_crossings')
  end subroutine chain_across_the_boundary

  !> A ring of 10 spheres along x through the box (10 x 2 r = L), a sheet of 10 x 10 and a cube of
  !> 10 x 10 x 10 on the periodic lattice: each connected to its own images in 1, 2 and 3 directions.
  subroutine percolating_clusters()
    integer, parameter :: m = 10
    real(wp), allocatable :: x(:,:)
    integer, allocatable :: pairs(:,:)
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    type(agglomerates_t) :: a
    type(fractal_fit_t) :: fit
    integer :: dims, found(3)
    do dims = 1, 3
      call lattice(m, dims, x, pairs)
      call spheres_at(x, shapes, bodies)
      call agglomerates_analyse(shapes, bodies, periodic, bonds_of(pairs, x, periodic), a)
      found(dims) = merge(a%percolation_rank(1), -1, a%clusters == 1 .and. a%percolating(1) &
                          .and. a%percolating_clusters == 1)
    end do
    call check_equal(found(1), 1, 'ring_through_the_box_percolates_in_1_direction')
    call check_equal(found(2), 2, 'sheet_through_the_box_percolates_in_2_directions')
    call check_equal(found(3), 3, 'lattice_through_the_box_percolates_in_3_directions')
    ! The fractal fit leaves a percolating cluster out.
    fit = cluster_fractal_dimension(a, r, 1)
    call check(fit%clusters == 0 .and. ieee_is_nan(fit%dimension), 'fractal_fit_leaves_percolating_out_nan_without_points')
  end subroutine percolating_clusters

  !> Simple cubic lattice of m^dims spheres, spacing 2 r, filling dims directions of the box; bonds to
  !> the next body along each of them, wrapping round.
  subroutine lattice(m, dims, x, pairs)
    integer, intent(in) :: m, dims
    real(wp), allocatable, intent(out) :: x(:,:)
    integer, allocatable, intent(out) :: pairs(:,:)
    integer :: counts(3), i, j, k, d, b, index_of(0:m - 1, 0:m - 1, 0:m - 1), step(3)
    real(wp) :: site(3)
    counts = 1
    counts(1:dims) = m
    allocate(x(3, product(counts)), pairs(2, dims * product(counts)))
    b = 0
    do k = 0, counts(3) - 1
      do j = 0, counts(2) - 1
        do i = 0, counts(1) - 1
          b = b + 1
          index_of(i, j, k) = b
          x(:, b) = 0.5_wp * periodic
          site = 2.0_wp * r * (real([i, j, k], wp) + 0.5_wp)
          x(1:dims, b) = site(1:dims)
        end do
      end do
    end do
    b = 0
    do k = 0, counts(3) - 1
      do j = 0, counts(2) - 1
        do i = 0, counts(1) - 1
          do d = 1, dims
            step = 0
            step(d) = 1
            b = b + 1
            pairs(:, b) = [index_of(i, j, k), index_of(mod(i + step(1), m), mod(j + step(2), m), mod(k + step(3), m))]
          end do
        end do
      end do
    end do
  end subroutine lattice

  !> Three clusters among six bodies: {1, 3, 5} (bonds given out of order), {2, 6}, {4} alone.
  subroutine separate_clusters()
    real(wp) :: x(3, 6)
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    type(agglomerates_t) :: a
    x(:, 1) = [0.2_wp, 0.2_wp, 0.2_wp] * box
    x(:, 3) = x(:, 1) + [2.0_wp * r, 0.0_wp, 0.0_wp]
    x(:, 5) = x(:, 3) + [0.0_wp, 2.0_wp * r, 0.0_wp]
    x(:, 2) = [0.7_wp, 0.6_wp, 0.5_wp] * box
    x(:, 6) = x(:, 2) + [0.0_wp, 0.0_wp, 2.0_wp * r]
    x(:, 4) = [0.5_wp, 0.2_wp, 0.8_wp] * box
    call spheres_at(x, shapes, bodies)
    call agglomerates_analyse(shapes, bodies, periodic, bonds_of(reshape([5, 3, 6, 2, 3, 1], [2, 3]), x, periodic), a)
    call check_equal(a%clusters, 3, 'three_clusters')
    call check(all(a%cluster_of == [1, 2, 1, 3, 1, 2]), 'clusters_numbered_by_smallest_member')
    call check(all(a%members == [1, 3, 5, 2, 6, 4]) .and. all(a%member_start == [1, 4, 6, 7]) .and. &
               all(a%cluster_size == [3, 2, 1]), 'members_listed_per_cluster')
    call check(all(a%cluster_bonds == [2, 1, 0]), 'bonds_per_cluster')
    call check(all(a%size_counts == [1, 1, 1]) .and. a%largest == 3, 'size_distribution_and_largest')
    call check_close(a%mean_size_number, 2.0_wp, 1.0e-15_wp, 'mean_size_number_N_over_K')
    ! (1^2 + 2^2 + 3^2) / 6
    call check_close(a%mean_size_weight, 14.0_wp / 6.0_wp, 1.0e-15_wp, 'mean_size_weight_sum_s2_over_N')
  end subroutine separate_clusters

  !> Three touching spheres in a random plane, centred on the box corner: the cycle of bonds crosses
  !> the boundary but does not wind around the box.
  subroutine triangle_across_the_boundary()
    real(wp) :: x(3, 3), rotation(3, 3), centre(3), expected(3)
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    type(agglomerates_t) :: a
    integer :: k
    real(wp) :: angle
    rotation = rotation_matrix(random_orientation(stream))
    centre = [0.9995_wp, 0.5_wp, 0.0003_wp] * box
    do k = 1, 3
      angle = pi / 2.0_wp + 2.0_wp * pi * real(k - 1, wp) / 3.0_wp
      x(:, k) = modulo(centre + matmul(rotation, 2.0_wp * r / sqrt(3.0_wp) * [cos(angle), sin(angle), 0.0_wp]), box)
    end do
    call spheres_at(x, shapes, bodies)
    call agglomerates_analyse(shapes, bodies, periodic, bonds_of(reshape([1, 2, 2, 3, 3, 1], [2, 3]), x, periodic), a)
    call check_close(a%radius_of_gyration(1)**2, (4.0_wp / 3.0_wp + 0.6_wp) * r**2, 1.0e-12_wp, 'triangle_rg2_4r2_over_3')
    expected = [0.2_wp, 2.0_wp / 3.0_wp + 0.2_wp, 2.0_wp / 3.0_wp + 0.2_wp] * r**2
    call check_below(maxval(abs(a%gyration_eigenvalues(:, 1) - expected)) / expected(3), 1.0e-12_wp, &
                     'triangle_gyration_eigenvalues')
    call check(.not. a%percolating(1) .and. a%percolation_rank(1) == 0, 'triangle_across_boundary_not_percolating')
    call check(all(a%coordination == 2) .and. abs(a%cluster_coordination(1) - 2.0_wp) <= 1.0e-15_wp, &
               'triangle_coordination_2')
  end subroutine triangle_across_the_boundary

  subroutine tetrahedron()
    real(wp) :: x(3, 4), rotation(3, 3), expected
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    type(agglomerates_t) :: a
    real(wp), parameter :: corners(3, 4) = reshape([1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1], [3, 4]) * 1.0_wp
    integer :: k
    rotation = rotation_matrix(random_orientation(stream))
    do k = 1, 4
      ! Corners of the cube's alternate vertices: edge 2 sqrt(2), scaled to 2 r.
      x(:, k) = 0.4_wp * periodic + matmul(rotation, r / sqrt(2.0_wp) * corners(:, k))
    end do
    call spheres_at(x, shapes, bodies)
    call agglomerates_analyse(shapes, bodies, periodic, &
                              bonds_of(reshape([1, 2, 1, 3, 1, 4, 2, 3, 2, 4, 3, 4], [2, 6]), x, periodic), a)
    expected = (0.5_wp + 0.2_wp) * r**2
    call check_below(maxval(abs(a%gyration_eigenvalues(:, 1) - expected)) / expected, 1.0e-12_wp, &
                     'tetrahedron_eigenvalues_equal_r2_over_2')
    call check_close(a%radius_of_gyration(1)**2, (1.5_wp + 0.6_wp) * r**2, 1.0e-12_wp, 'tetrahedron_rg2_3r2_over_2')
    call check(all(a%coordination == 3), 'tetrahedron_coordination_3')
  end subroutine tetrahedron

  !> Two touching spheres of the same size, the second three times as dense: the centre of mass a
  !> quarter of the way from the second, R_g^2 = m1 m2 d^2 / M^2 = 3/16 (2 r)^2 over the centres.
  subroutine unequal_masses()
    type(spheroid_t) :: shapes(2)
    type(rigid_body_t) :: bodies(2)
    type(agglomerates_t) :: a
    real(wp) :: x(3, 2), e(3)
    e = random_unit_vector()
    x(:, 1) = 0.5_wp * periodic
    x(:, 2) = x(:, 1) + 2.0_wp * r * e
    shapes(1) = make_spheroid('sphere', r, density)
    shapes(2) = make_spheroid('sphere', r, 3.0_wp * density)
    call rigid_body_of_spheroid(bodies(1), shapes(1), x(:, 1), quaternion_identity)
    call rigid_body_of_spheroid(bodies(2), shapes(2), x(:, 2), quaternion_identity)
    call agglomerates_analyse(shapes, bodies, periodic, bonds_of(reshape([1, 2], [2, 1]), x, periodic), a)
    call check_below(maxval(abs(a%centre_of_mass(:, 1) - (x(:, 1) + 3.0_wp * x(:, 2)) / 4.0_wp)), 1.0e-15_wp * box, &
                     'unequal_masses_centre_of_mass')
    call check_close(a%radius_of_gyration_centres(1)**2, 0.75_wp * r**2, 1.0e-12_wp, 'unequal_masses_rg_mass_weighted')
  end subroutine unequal_masses

  !> 300 random graphs (up to 60 bodies, up to 1.5 bonds per body): union-find components equal
  !> a brute-force labelling (breadth-first search over the adjacency matrix, components numbered
  !> by their smallest body).
  subroutine random_graphs()
    integer :: trial, n, n_bonds, b, i, j, components, k
    integer, allocatable :: first(:), second(:), labels(:), reference(:)
    logical, allocatable :: linked(:,:)
    logical :: same_labels, same_analysis, bond_counts
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    type(bond_t), allocatable :: bonds(:)
    type(agglomerates_t) :: a
    real(wp), allocatable :: x(:,:)
    same_labels = .true.
    same_analysis = .true.
    bond_counts = .true.
    do trial = 1, 300
      n = 1 + int(60.0_wp * stream_uniform(stream))
      n_bonds = 0
      if (n > 1) n_bonds = int(1.5_wp * n * stream_uniform(stream))
      n_bonds = min(n_bonds, n * (n - 1) / 2)
      allocate(first(n_bonds), second(n_bonds), labels(n), reference(n), linked(n, n), x(3, n))
      linked = .false.
      b = 0
      do while (b < n_bonds)
        i = 1 + int(n * stream_uniform(stream))
        j = 1 + int(n * stream_uniform(stream))
        if (i == j .or. linked(i, j)) cycle
        b = b + 1
        first(b) = i
        second(b) = j
        linked(i, j) = .true.
        linked(j, i) = .true.
      end do
      call brute_force_labels(linked, reference)
      do k = 1, n
        x(:, k) = [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)] * box
      end do
      bonds = bonds_of(reshape([(first(b), second(b), b = 1, n_bonds)], [2, n_bonds]), x, periodic)
      call component_labels(n, bonds, labels, components)
      same_labels = same_labels .and. all(labels == reference) .and. components == maxval(reference)
      call spheres_at(x, shapes, bodies)
      call agglomerates_analyse(shapes, bodies, periodic, bonds, a)
      same_analysis = same_analysis .and. all(a%cluster_of == reference) .and. a%clusters == maxval(reference)
      bond_counts = bond_counts .and. sum(a%coordination) == 2 * n_bonds .and. sum(a%cluster_bonds) == n_bonds &
                    .and. sum(a%size_counts * [(k, k = 1, a%largest)]) == n
      deallocate(first, second, labels, reference, linked, x)
    end do
    call check(same_labels, 'union_find_equals_brute_force_components')
    call check(same_analysis, 'analysis_clusters_equal_brute_force_components')
    call check(bond_counts, 'coordination_sums_to_2B_and_sizes_to_N')
  end subroutine random_graphs

  subroutine brute_force_labels(linked, labels)
    logical, intent(in) :: linked(:,:)
    integer, intent(out) :: labels(:)
    integer :: queue(size(labels)), head, tail, i, u, v, next
    labels = 0
    next = 0
    do i = 1, size(labels)
      if (labels(i) /= 0) cycle
      next = next + 1
      labels(i) = next
      queue(1) = i
      head = 1
      tail = 1
      do while (head <= tail)
        u = queue(head)
        head = head + 1
        do v = 1, size(labels)
          if (linked(u, v) .and. labels(v) == 0) then
            labels(v) = next
            tail = tail + 1
            queue(tail) = v
          end if
        end do
      end do
    end do
  end subroutine brute_force_labels

  !> 10^5 spheres in one straight chain in an unbounded box, bonds listed backwards (the
  !> union-find trees and the walk are deep): one cluster, R_g of the chain formula.
  subroutine long_chain()
    integer, parameter :: n = 100000
    real(wp), allocatable :: x(:,:)
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    type(bond_t), allocatable :: bonds(:)
    type(agglomerates_t) :: a
    integer :: k
    x = chain_positions(n, [0.0_wp, 0.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp])
    call spheres_at(x, shapes, bodies)
    allocate(bonds(n - 1))
    do k = 1, n - 1
      bonds(k) = bond_t(n - k, n - k + 1, [0, 0, 0])
    end do
    call agglomerates_analyse(shapes, bodies, unbounded, bonds, a)
    call check(a%clusters == 1 .and. a%largest == n .and. size(a%size_counts) == n, 'long_chain_one_cluster')
    call check_close(a%radius_of_gyration_centres(1)**2, r**2 * (real(n, wp)**2 - 1.0_wp) / 3.0_wp, 1.0e-10_wp, &
                     'long_chain_rg_centres')
  end subroutine long_chain

  !> Needle 1 bonded to needles at 30, 90 and 150 degrees from it (a turn about a common axis, the
  !> set then turned as a whole at random): psi = 30, 90 and 30 degrees (axes are lines).
  subroutine needle_angles()
    type(spheroid_t) :: shapes(4)
    type(rigid_body_t) :: bodies(4)
    type(agglomerates_t) :: a
    real(wp) :: common(4), angles(4), x(3, 4)
    integer :: k
    common = random_orientation(stream)
    angles = [0.0_wp, 30.0_wp, 90.0_wp, 150.0_wp] * pi / 180.0_wp
    do k = 1, 4
      shapes(k) = make_spheroid('needle', r, density)
      x(:, k) = 0.5_wp * periodic + [0.0_wp, 0.0_wp, 4.0_wp * r * (k - 1)]
      call rigid_body_of_spheroid(bodies(k), shapes(k), x(:, k), &
                                  quaternion_product(common, quaternion_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], angles(k))))
    end do
    call agglomerates_analyse(shapes, bodies, periodic, bonds_of(reshape([1, 2, 1, 3, 1, 4], [2, 3]), x, periodic), a)
    call check_close(a%psi(1), pi / 6.0_wp, 0.0_wp, 'psi_30_degrees', abs_tol=1.0e-14_wp)
    call check_close(a%psi(2), pi / 2.0_wp, 0.0_wp, 'psi_90_degrees', abs_tol=1.0e-14_wp)
    call check_close(a%psi(3), pi / 6.0_wp, 0.0_wp, 'psi_150_degrees_folds_to_30', abs_tol=1.0e-14_wp)
  end subroutine needle_angles

  subroutine fractal_fits()
    integer, parameter :: m = 60, samples = 2000, per_sample = 50
    real(wp), parameter :: dimension = 1.8_wp, prefactor = 1.3_wp
    real(wp), parameter :: t975_48 = 2.0106348_wp   ! Student's t, 97.5% quantile, 48 degrees of freedom
    integer :: sizes(m), k, sample, covered
    real(wp) :: rg(m), noisy(per_sample), abscissa(per_sample), expected(4)
    logical :: include(m)
    type(fractal_fit_t) :: fit
    type(linear_fit_t) :: line
    ! Exact power law N = k_f (R_g / r)^D_f for N = 3..60; sizes 1 and 2 off the law (left out by
    ! min_size = 3) and one cluster off the law left out by include.
    do k = 1, m
      sizes(k) = k
      rg(k) = r * (real(k, wp) / prefactor)**(1.0_wp / dimension)
    end do
    rg(1:2) = 10.0_wp * rg(1:2)
    include = .true.
    rg(40) = 0.1_wp * rg(40)
    include(40) = .false.
    fit = fractal_dimension_fit(sizes, rg, r, 3, include)
    call check(fit%clusters == m - 3, 'fractal_fit_uses_clusters_of_min_size_and_included')
    call check_close(fit%dimension, dimension, 1.0e-10_wp, 'fractal_fit_recovers_dimension')
    call check_close(fit%prefactor, prefactor, 1.0e-10_wp, 'fractal_fit_recovers_prefactor')
    call check_below(fit%dimension_error, 1.0e-10_wp, 'fractal_fit_exact_data_no_error')
    ! A worked least-squares line: x = 1..5, y = (2, 4, 5, 4, 5): slope 0.6, intercept 2.2, residual
    ! variance 2.4 / 3 = 0.8, se(slope) = sqrt(0.8 / 10), se(intercept) = sqrt(0.8 (1/5 + 9/10)).
    line = linear_fit([1.0_wp, 2.0_wp, 3.0_wp, 4.0_wp, 5.0_wp], [2.0_wp, 4.0_wp, 5.0_wp, 4.0_wp, 5.0_wp])
    expected = [0.6_wp, 2.2_wp, sqrt(0.08_wp), sqrt(0.88_wp)]
    call check_below(maxval(abs([line%slope, line%intercept, line%slope_error, line%intercept_error] - expected)), &
                     1.0e-14_wp, 'linear_fit_worked_example')
    ! Coverage of the interval: y = 0.3 + 1.8 x + Gaussian scatter (sd 0.1) at 50 points x = ln(3..52);
    ! slope +- t(48) se must hold 1.8 in 95% of 2000 samples (binomial sd 0.5%).
    covered = 0
    do k = 1, per_sample
      abscissa(k) = log(real(k + 2, wp))
    end do
    do sample = 1, samples
      do k = 1, per_sample
        noisy(k) = 0.3_wp + dimension * abscissa(k) + 0.1_wp * stream_normal(stream)
      end do
      line = linear_fit(abscissa, noisy)
      if (abs(line%slope - dimension) <= t975_48 * line%slope_error) covered = covered + 1
    end do
    call check_close(real(covered, wp) / samples, 0.95_wp, 0.0_wp, 'linear_fit_interval_covers_95_percent', &
                     abs_tol=0.02_wp)
  end subroutine fractal_fits

  !> Q diag(lambda) Q^T for random rotations Q, with distinct, pairwise equal and all equal lambda:
  !> symmetric_eigenvalues3 returns lambda, ascending, to round-off of the norm.
  subroutine eigenvalues_of_rotated_tensors()
    real(wp) :: rotation(3, 3), lambda(3), diagonal(3, 3), worst
    integer :: trial, k
    worst = 0.0_wp
    do trial = 1, 1000
      lambda = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
      select case (mod(trial, 4))
      case (1); lambda(2) = lambda(1)
      case (2); lambda = lambda(3)
      case (3); lambda(1) = 0.0_wp
      end select
      rotation = rotation_matrix(random_orientation(stream))
      diagonal = 0.0_wp
      do k = 1, 3
        diagonal(k, k) = lambda(k)
      end do
      lambda = sorted_values(lambda)
      worst = max(worst, maxval(abs(symmetric_eigenvalues3(matmul(rotation, matmul(diagonal, transpose(rotation)))) &
                                    - lambda)) / maxval(abs(lambda)))
    end do
    call check_below(worst, 1.0e-14_wp, 'symmetric_eigenvalues3_of_rotated_diagonals')
  end subroutine eigenvalues_of_rotated_tensors

end program test_agglomerates
