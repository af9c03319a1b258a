!> Agglomerates: the clusters of bonded bodies at one instant and their measures (docs/theory.md,
!> "Agglomerates").
!>
!> Input: the bodies (shapes, and states with positions in the box and orientations), the box
!> periods and the bonds. A bond (i, j, n) (bond_t, module bond_graph) says that body j at its image
!> x_j + n L (n integer periods per direction, L the box lengths, elementwise) is bonded to body i
!> at x_i. The positions may be wrapped into the box or continuous (unwrapped) as long as every
!> bond's image belongs to the positions given: bond_image gives the minimum image of a bond formed
!> now, and carried_bond_image keeps a bond's image true while its bodies cross the box boundaries.
!>
!> Output (agglomerates_t), per call:
!>  - clusters: the connected components of the bond graph (union-find, module bond_graph), numbered
!>    in the order of their smallest body; a body without bonds is a cluster of size 1;
!>  - the size distribution, the number- and weight-averaged mean sizes and the largest size;
!>  - per body: its cluster, its position unwrapped within its cluster (a breadth-first walk of the
!>    bonds from the cluster's smallest body, adding each bond's image: a cluster that spans the
!>    periodic boundary is made contiguous) and its coordination number (bonds per body);
!>  - per cluster: members, mass, centre of mass (wrapped into the box), radius of gyration (mass
!>    weighted, with each spheroid's own gyration tensor unless body_extent = .false.; also over
!>    the centres alone), gyration-tensor eigenvalues, bonds and mean coordination, and whether it
!>    percolates (a cycle of bonds whose images add up to a non-zero lattice vector: the cluster is
!>    connected to its own periodic image, so it has no finite unwrapped shape; its measures are
!>    those of the spanning tree the walk took and must not enter fractal fits);
!>  - per bond: psi, the angle between the symmetry axes of the two bodies in [0, pi/2].
!> fractal_dimension_fit: the least-squares fractal dimension and prefactor of N = k_f (R_g / r)^D_f.
module agglomerates
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use spheroid, only: spheroid_t
  use rigid_body, only: rigid_body_t
  use quaternion, only: symmetry_axis
  use vector_algebra, only: outer, symmetric_eigenvalues3
  use closest_points, only: symmetry_axis_angle
  use periodic_box, only: image_periods
  use bond_graph, only: bond_t, component_labels, adjacency_t, adjacency_build
  use sample_statistics, only: linear_fit_t, linear_fit
  implicit none
  private
  public :: bond_t, agglomerates_t, agglomerates_analyse, bond_image, carried_bond_image, &
            fractal_fit_t, fractal_dimension_fit, cluster_fractal_dimension

  !> The agglomerates of N bodies and B bonds at one instant (K clusters). Arrays over bodies,
  !> clusters and bonds in the order of the input bodies, of the cluster numbers and of the bonds.
  type :: agglomerates_t
    integer :: bodies = 0, bonds = 0, clusters = 0
    integer :: largest = 0                       !< members of the largest cluster
    real(wp) :: mean_size_number = 0.0_wp        !< sum_s s n_s / sum_s n_s = N / K
    real(wp) :: mean_size_weight = 0.0_wp        !< sum_s s^2 n_s / sum_s s n_s = sum_s s^2 n_s / N
    real(wp) :: mean_coordination = 0.0_wp       !< 2 B / N: bonds per body over all bodies
    integer :: percolating_clusters = 0
    integer, allocatable :: size_counts(:)       !< (largest): n_s, the number of clusters of s members
    ! Per body (N).
    integer, allocatable :: cluster_of(:)        !< cluster number, 1..K
    integer, allocatable :: coordination(:)      !< bonds of the body
    integer, allocatable :: image(:,:)           !< (3, N) periods added to the position by the unwrapping
    real(wp), allocatable :: unwrapped(:,:)      !< (3, N) m, position + image * box_length
    ! Per cluster (K); the members of cluster c are members(member_start(c) : member_start(c+1) - 1),
    ! ascending; the first is the root of the unwrapping (its position is kept).
    integer, allocatable :: member_start(:)      !< (K + 1)
    integer, allocatable :: members(:)           !< (N)
    integer, allocatable :: cluster_size(:)      !< members
    integer, allocatable :: cluster_bonds(:)     !< bonds between members
    real(wp), allocatable :: cluster_coordination(:)   !< 2 bonds / members
    real(wp), allocatable :: mass(:)             !< kg
    real(wp), allocatable :: centre_of_mass(:,:) !< (3, K) m, wrapped into [0, L) in periodic directions
    real(wp), allocatable :: radius_of_gyration(:)          !< m, sqrt of the gyration tensor's trace
    real(wp), allocatable :: radius_of_gyration_centres(:)  !< m, over the body centres alone
    real(wp), allocatable :: gyration_eigenvalues(:,:)      !< (3, K) m^2, ascending, of the gyration tensor
    logical, allocatable :: percolating(:)       !< connected to its own periodic image
    integer, allocatable :: percolation_rank(:)  !< independent lattice directions it spans (0..3)
    ! Per bond (B).
    real(wp), allocatable :: psi(:)              !< rad, angle between the symmetry axes, [0, pi/2]
  end type agglomerates_t

  !> N = k_f (R_g / r)^D_f fitted to clusters: ln N = ln k_f + D_f ln(R_g / r) by least squares.
  type :: fractal_fit_t
    integer :: clusters = 0                      !< clusters in the fit
    real(wp) :: dimension = 0.0_wp               !< D_f
    real(wp) :: dimension_error = 0.0_wp         !< standard error of D_f
    real(wp) :: prefactor = 0.0_wp               !< k_f
    real(wp) :: log_prefactor_error = 0.0_wp     !< standard error of ln k_f
  end type fractal_fit_t

contains

  !> The agglomerates of the bodies (shapes(i), bodies(i)) in a box of periods box_length (0: an
  !> unbounded direction) with the given bonds. body_extent (default .true.): the gyration tensor
  !> and R_g include each spheroid's own gyration tensor, so a single body has R_g > 0.
  !> A bond naming a body outside 1..N, a body bonded to itself, a pair bonded twice or a non-zero
  !> image in an unbounded direction is a programming error of the caller: fatal.
  subroutine agglomerates_analyse(shapes, bodies, box_length, bonds, result, body_extent)
    type(spheroid_t), intent(in) :: shapes(:)
    type(rigid_body_t), intent(in) :: bodies(:)
    real(wp), intent(in) :: box_length(3)
    type(bond_t), intent(in) :: bonds(:)
    type(agglomerates_t), intent(out) :: result
    logical, intent(in), optional :: body_extent
    type(adjacency_t) :: adjacency
    integer, allocatable :: fill(:)
    integer :: n, k, i, c, b
    logical :: extent

    extent = .true.
    if (present(body_extent)) extent = body_extent
    n = size(bodies)
    if (size(shapes) /= n) call fatal('agglomerates: shapes and bodies differ in number', collective=.false.)
    call check_bonds(n, bonds, box_length)
    result%bodies = n
    result%bonds = size(bonds)

    ! Clusters and their members (counting sort by cluster: members ascending within a cluster).
    allocate(result%cluster_of(n))
    call component_labels(n, bonds, result%cluster_of, k)
    result%clusters = k
    allocate(result%member_start(k + 1), result%members(n), result%cluster_size(k), fill(k))
    result%cluster_size = 0
    do i = 1, n
      result%cluster_size(result%cluster_of(i)) = result%cluster_size(result%cluster_of(i)) + 1
    end do
    result%member_start(1) = 1
    do c = 1, k
      result%member_start(c + 1) = result%member_start(c) + result%cluster_size(c)
    end do
    fill = result%member_start(1:k)
    do i = 1, n
      c = result%cluster_of(i)
      result%members(fill(c)) = i
      fill(c) = fill(c) + 1
    end do

    ! Bonds per body and per cluster.
    call adjacency_build(n, bonds, adjacency)
    call check_duplicates(n, adjacency)
    allocate(result%coordination(n), result%cluster_bonds(k), result%cluster_coordination(k))
    result%coordination = adjacency%start(2:n + 1) - adjacency%start(1:n)
    result%cluster_bonds = 0
    do b = 1, size(bonds)
      c = result%cluster_of(bonds(b)%first)
      result%cluster_bonds(c) = result%cluster_bonds(c) + 1
    end do
    result%cluster_coordination = 2.0_wp * real(result%cluster_bonds, wp) / real(result%cluster_size, wp)

    ! Unwrapping, percolation and the shape of each cluster.
    allocate(result%image(3, n), result%unwrapped(3, n), result%percolating(k), result%percolation_rank(k))
    call unwrap_clusters(bodies, box_length, bonds, adjacency, result)
    result%percolating = result%percolation_rank > 0
    result%percolating_clusters = count(result%percolating)
    allocate(result%mass(k), result%centre_of_mass(3, k), result%radius_of_gyration(k), &
             result%radius_of_gyration_centres(k), result%gyration_eigenvalues(3, k))
    do c = 1, k
      call cluster_shape(shapes, bodies, result%unwrapped, result%members(result%member_start(c):result%member_start(c + 1) - 1), &
                         box_length, extent, result%mass(c), result%centre_of_mass(:, c), result%radius_of_gyration(c), &
                         result%radius_of_gyration_centres(c), result%gyration_eigenvalues(:, c))
    end do

    allocate(result%psi(size(bonds)))
    do b = 1, size(bonds)
      result%psi(b) = symmetry_axis_angle(bodies(bonds(b)%first)%quaternion, bodies(bonds(b)%second)%quaternion)
    end do

    ! Size distribution and means (Stauffer & Aharony 1994, ch. 2: the weight average is the mean
    ! size of the cluster a body picked at random belongs to).
    result%largest = 0
    if (k > 0) result%largest = maxval(result%cluster_size)
    allocate(result%size_counts(result%largest))
    result%size_counts = 0
    do c = 1, k
      result%size_counts(result%cluster_size(c)) = result%size_counts(result%cluster_size(c)) + 1
    end do
    if (n > 0) then
      result%mean_size_number = real(n, wp) / real(k, wp)
      result%mean_size_weight = sum(real(result%cluster_size, wp)**2) / real(n, wp)
      result%mean_coordination = 2.0_wp * real(size(bonds), wp) / real(n, wp)
    end if
  end subroutine agglomerates_analyse

  !> The image of a bond formed now: body second's minimum image next to body first (periods).
  pure function bond_image(first_position, second_position, box_length) result(image)
    real(wp), intent(in) :: first_position(3), second_position(3), box_length(3)
    integer :: image(3)
    image = image_periods(second_position - first_position, box_length)
  end function bond_image

  !> A bond's image after its bodies crossed the box boundaries (crossings: the change of
  !> particle_system's wraps since the image was taken). Body second wrapped back by one period
  !> needs one more period to sit next to first again, and the other way round for first.
  pure function carried_bond_image(image, first_crossings, second_crossings) result(carried)
    integer, intent(in) :: image(3)
    integer(i8), intent(in) :: first_crossings(3), second_crossings(3)
    integer :: carried(3)
    carried = image + int(second_crossings - first_crossings)
  end function carried_bond_image

  !> Breadth-first walk of each cluster from its first (smallest) member, which keeps its position:
  !> a body reached over bond (u, v, n) gets image(v) = image(u) + n (n negated when the bond is
  !> walked from its second body). A bond between two bodies already placed closes a cycle; the
  !> images around it add up to image(u) + n - image(v), zero unless the cycle winds around the box.
  !> The rank of those winding vectors is the number of independent directions the cluster spans.
  pure subroutine unwrap_clusters(bodies, box_length, bonds, adjacency, result)
    type(rigid_body_t), intent(in) :: bodies(:)
    real(wp), intent(in) :: box_length(3)
    type(bond_t), intent(in) :: bonds(:)
    type(adjacency_t), intent(in) :: adjacency
    type(agglomerates_t), intent(inout) :: result
    logical, allocatable :: placed(:)
    integer, allocatable :: queue(:)
    integer :: c, head, tail, u, v, e, n_uv(3), winding(3)
    integer(i8) :: basis(3, 3)

    allocate(placed(result%bodies), queue(result%bodies))
    placed = .false.
    do c = 1, result%clusters
      basis = 0_i8
      result%percolation_rank(c) = 0
      u = result%members(result%member_start(c))
      result%image(:, u) = 0
      placed(u) = .true.
      queue(1) = u
      head = 1
      tail = 1
      do while (head <= tail)
        u = queue(head)
        head = head + 1
        do e = adjacency%start(u), adjacency%start(u + 1) - 1
          v = adjacency%neighbour(e)
          n_uv = bonds(adjacency%bond(e))%image
          if (bonds(adjacency%bond(e))%first /= u) n_uv = -n_uv
          if (.not. placed(v)) then
            result%image(:, v) = result%image(:, u) + n_uv
            placed(v) = .true.
            tail = tail + 1
            queue(tail) = v
          else
            winding = result%image(:, u) + n_uv - result%image(:, v)
            if (any(winding /= 0)) call add_winding(basis, result%percolation_rank(c), int(winding, i8))
          end if
        end do
      end do
    end do
    do u = 1, result%bodies
      result%unwrapped(:, u) = bodies(u)%position + real(result%image(:, u), wp) * box_length
    end do
  end subroutine unwrap_clusters

  !> Add a winding vector to the basis of the lattice directions found so far if it is independent
  !> of them (exact integer cross and triple products).
  pure subroutine add_winding(basis, rank, winding)
    integer(i8), intent(inout) :: basis(3, 3)
    integer, intent(inout) :: rank
    integer(i8), intent(in) :: winding(3)
    logical :: independent
    select case (rank)
    case (0)
      independent = .true.
    case (1)
      independent = any(integer_cross(basis(:, 1), winding) /= 0_i8)
    case (2)
      independent = sum(integer_cross(basis(:, 1), basis(:, 2)) * winding) /= 0_i8
    case default
      independent = .false.
    end select
    if (.not. independent) return
    rank = rank + 1
    basis(:, rank) = winding
  end subroutine add_winding

  pure function integer_cross(a, b) result(c)
    integer(i8), intent(in) :: a(3), b(3)
    integer(i8) :: c(3)
    c = [a(2) * b(3) - a(3) * b(2), a(3) * b(1) - a(1) * b(3), a(1) * b(2) - a(2) * b(1)]
  end function integer_cross

  !> Mass, centre of mass and gyration of one cluster from its unwrapped positions. With masses m_i,
  !> M = sum m_i, centre x_c = sum m_i x_i / M and r_i = x_i - x_c:
  !>   G = (1/M) sum_i m_i (r_i r_i^T + S_i),  S_i = R_i diag(a^2, b^2, b^2) R_i^T / 5,
  !> S_i the gyration tensor of the solid spheroid about its centre (uniform density; its moments of
  !> inertia, Eq. 12 of the paper, are m (tr S - S)); R_g^2 = tr G. The centre is taken relative to
  !> the first member and the tensor in a second pass, so nothing cancels across the box length.
  !> Eigenvalues below zero by round-off (a straight chain's centres) are returned as 0.
  pure subroutine cluster_shape(shapes, bodies, unwrapped, members, box_length, extent, mass, centre, &
                                radius_of_gyration, radius_of_gyration_centres, eigenvalues)
    type(spheroid_t), intent(in) :: shapes(:)
    type(rigid_body_t), intent(in) :: bodies(:)
    real(wp), intent(in) :: unwrapped(:,:), box_length(3)
    integer, intent(in) :: members(:)
    logical, intent(in) :: extent
    real(wp), intent(out) :: mass, centre(3), radius_of_gyration, radius_of_gyration_centres, eigenvalues(3)
    real(wp) :: origin(3), offset(3), spread(3, 3), own(3, 3), axis(3), m
    integer :: k, i, d

    origin = unwrapped(:, members(1))
    mass = 0.0_wp
    offset = 0.0_wp
    do k = 1, size(members)
      i = members(k)
      mass = mass + shapes(i)%mass
      offset = offset + shapes(i)%mass * (unwrapped(:, i) - origin)
    end do
    offset = offset / mass
    spread = 0.0_wp
    own = 0.0_wp
    do k = 1, size(members)
      i = members(k)
      m = shapes(i)%mass
      spread = spread + m * outer(unwrapped(:, i) - origin - offset, unwrapped(:, i) - origin - offset)
      if (.not. extent) cycle
      ! R diag(a^2, b^2, b^2) R^T = b^2 I + (a^2 - b^2) e e^T with e the symmetry axis (body x).
      axis = symmetry_axis(bodies(i)%quaternion)
      own = own + m * (shapes(i)%a**2 - shapes(i)%b**2) / 5.0_wp * outer(axis, axis)
      do d = 1, 3
        own(d, d) = own(d, d) + m * shapes(i)%b**2 / 5.0_wp
      end do
    end do
    spread = spread / mass
    own = own / mass
    radius_of_gyration_centres = sqrt(spread(1, 1) + spread(2, 2) + spread(3, 3))
    radius_of_gyration = sqrt(spread(1, 1) + spread(2, 2) + spread(3, 3) + own(1, 1) + own(2, 2) + own(3, 3))
    eigenvalues = max(symmetric_eigenvalues3(spread + own), 0.0_wp)
    centre = origin + offset
    do d = 1, 3
      if (box_length(d) > 0.0_wp) then
        centre(d) = modulo(centre(d), box_length(d))
        if (centre(d) >= box_length(d)) centre(d) = 0.0_wp   ! modulo of a tiny negative number rounds to L
      end if
    end do
  end subroutine cluster_shape

  !> Every bond names two different bodies in 1..n and has no image in an unbounded direction.
  subroutine check_bonds(n, bonds, box_length)
    integer, intent(in) :: n
    type(bond_t), intent(in) :: bonds(:)
    real(wp), intent(in) :: box_length(3)
    integer :: b
    character(len=160) :: text
    character(len=48) :: problem
    do b = 1, size(bonds)
      associate (i => bonds(b)%first, j => bonds(b)%second)
        problem = ''
        if (min(i, j) < 1 .or. max(i, j) > n) then
          write(problem, '(a,i0)') 'names a body outside 1..', n
        else if (i == j) then
          problem = 'bonds a body to itself'
        else if (any(bonds(b)%image /= 0 .and. .not. box_length > 0.0_wp)) then
          problem = 'has an image in an unbounded direction'
        end if
        if (len_trim(problem) == 0) cycle
        write(text, '(a,i0,a,i0,a,i0,a,3(1x,i0),a)') 'agglomerates: bond ', b, ' (', i, ', ', j, ', image', &
          bonds(b)%image, ') '
        call fatal(trim(text)//' '//trim(problem), collective=.false.)
      end associate
    end do
  end subroutine check_bonds

  !> No pair is bonded twice (in either order): a body's row of the adjacency names each neighbour
  !> once. last_row(v) = u marks v as seen in row u, so the check is O(N + B).
  subroutine check_duplicates(n, adjacency)
    integer, intent(in) :: n
    type(adjacency_t), intent(in) :: adjacency
    integer, allocatable :: last_row(:)
    integer :: u, e, v
    character(len=96) :: text
    allocate(last_row(n))
    last_row = 0
    do u = 1, n
      do e = adjacency%start(u), adjacency%start(u + 1) - 1
        v = adjacency%neighbour(e)
        if (last_row(v) == u) then
          write(text, '(a,i0,a,i0,a)') 'agglomerates: the pair (', min(u, v), ', ', max(u, v), ') is bonded twice'
          call fatal(trim(text), collective=.false.)
        end if
        last_row(v) = u
      end do
    end do
  end subroutine check_duplicates

  !> The fractal dimension and prefactor of N = k_f (R_g / radius)^D_f (Sorensen 2001, Aerosol Sci.
  !> Technol. 35, 648) by least squares of ln N on ln(R_g / radius) over the clusters with
  !> at least min_size members (and include, if given: e.g. .not. percolating). radius: the
  !> volume-equivalent radius of one body. A cluster with R_g <= 0 (a single body's R_g over centres
  !> alone) has no logarithm and is left out. Fewer than two distinct R_g: NaN dimension; fewer
  !> than three clusters: NaN errors (sample_statistics, linear_fit). An interval for D_f is
  !> dimension +- t(clusters - 2) dimension_error.
  pure function fractal_dimension_fit(sizes, radius_of_gyration, radius, min_size, include) result(fit)
    integer, intent(in) :: sizes(:), min_size
    real(wp), intent(in) :: radius_of_gyration(:), radius
    logical, intent(in), optional :: include(:)
    type(fractal_fit_t) :: fit
    logical, allocatable :: used(:)
    type(linear_fit_t) :: line
    used = sizes >= min_size .and. radius_of_gyration > 0.0_wp
    if (present(include)) used = used .and. include
    line = linear_fit(log(pack(radius_of_gyration, used) / radius), log(real(pack(sizes, used), wp)))
    fit%clusters = line%points
    fit%dimension = line%slope
    fit%dimension_error = line%slope_error
    fit%prefactor = exp(line%intercept)
    fit%log_prefactor_error = line%intercept_error
  end function fractal_dimension_fit

  !> fractal_dimension_fit over the clusters of one analysis, percolating clusters left out.
  pure function cluster_fractal_dimension(clusters, radius, min_size) result(fit)
    type(agglomerates_t), intent(in) :: clusters
    real(wp), intent(in) :: radius
    integer, intent(in) :: min_size
    type(fractal_fit_t) :: fit
    fit = fractal_dimension_fit(clusters%cluster_size, clusters%radius_of_gyration, radius, min_size, &
                                include=.not. clusters%percolating)
  end function cluster_fractal_dimension

end module agglomerates
