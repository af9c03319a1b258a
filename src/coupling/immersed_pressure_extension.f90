!> The pressure of the sealed cells next to the fluid, extrapolated from the open cells after every
!> step when the bodies move (docs/theory.md, "Immersed boundary: moving bodies"): a cell the body
!> uncovers then enters the incremental predictor's old pressure gradient with the fluid's pressure,
!> not with the unbounded pressure the projection leaves inside the body.
module immersed_pressure_extension
  use, intrinsic :: iso_fortran_env, only: int8
  use agglo_kinds, only: wp
  use fluid_grid, only: fluid_grid_t
  use halo_exchange, only: exchange_slab_halos
  use immersed_geometry, only: node_fluid
  use immersed_nodes, only: wrap
  use immersed_boundary, only: immersed_boundary_t
  implicit none
  private
  public :: ibm_extend_pressure

  !> The cells near one body's (or one edge plane's) solid nodes, row by row: for the rows (j, k)
  !> with j = j_first..j_last (unwrapped: the global row is wrap(j)) and k = k_first..k_last (local),
  !> the cells i = lo(j, k)..hi(j, k) (unwrapped; none when lo > hi).
  type :: cell_band_t
    integer :: j_first = 1, j_last = 0, k_first = 1, k_last = 0
    integer, allocatable :: lo(:, :), hi(:, :)
  end type cell_band_t

contains

  !> The pressure of the sealed cells next to the fluid (collective; call after the projection,
  !> with the classification of the velocity just projected and every pressure halo current).
  !> A sealed cell has no fluid face: its pressure enters no fluid node's gradient, and the
  !> projection, which sees the cut cells' divergence every step, lets it grow without bound (the
  !> increments phi are harmonic inside the body). When the body moves, a sealed cell next to the
  !> fluid can open in the next step, and its pressure then enters the incremental predictor's
  !> -(dt/rho) G p^{n-1/2} at the uncovered face. So every sealed cell with an open neighbour
  !> takes the mean over its open neighbours N1 = C + e (the six directions e) of the linear
  !> extrapolation 2 p(N1) - p(N1 + e) when N1 + e is open too, else p(N1): the gradient at a
  !> face that opens is then the gradient one cell further out (docs/theory.md, moving bodies).
  !> Open cells are never changed, so fixed bodies give the same velocity to the bit.
  subroutine ibm_extend_pressure(ibm, grid, pressure)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(inout) :: grid
    real(wp), intent(inout) :: pressure(0:, 0:, 0:)
    integer :: i, j, k, ii, jj, b, nx, ny, nzl, d, count
    real(wp) :: total
    integer, parameter :: step_x(4) = [1, -1, 0, 0], step_y(4) = [0, 0, 1, -1]
    type(cell_band_t), allocatable :: bands(:)
    nx = grid%nx; ny = grid%ny; nzl = grid%nz_local
    if (.not. allocated(ibm%cell_open)) then
      allocate(ibm%cell_open, ibm%offer_down, ibm%offer_up, mold=pressure)
      ibm%cell_open = 1; ibm%offer_down = 0; ibm%offer_up = 0
    end if
    ! Only cells within 3 (in each index) of a solid node are visited, body by body and row by row
    ! (near_bands); cell_open stays 1 elsewhere: a body moves less than a cell per step, so the
    ! cells it sealed before lie in its new band. Where bands overlap a cell is visited more than
    ! once, with the same result: each pass reads only what an earlier pass wrote or what it does
    ! not change (open cells keep their pressure).
    call near_bands(ibm, grid, 3, bands)
    associate (su => ibm%geometry%component(1)%status, sv => ibm%geometry%component(2)%status, &
               sw => ibm%geometry%component(3)%status, open => ibm%cell_open)
      ! A cell is open when one of its six faces (u(i-1), u(i), v(j-1), v(j), w(k-1), w(k)) is a fluid node.
      do b = 1, size(bands)
        do k = bands(b)%k_first, bands(b)%k_last
          do jj = bands(b)%j_first, bands(b)%j_last
            j = wrap(jj, ny)
            do ii = bands(b)%lo(jj, k), bands(b)%hi(jj, k)
              i = wrap(ii, nx)
              open(i, j, k) = merge(1.0_wp, 0.0_wp, su(i - 1, j, k) == node_fluid .or. su(i, j, k) == node_fluid .or. &
                                    sv(i, j - 1, k) == node_fluid .or. sv(i, j, k) == node_fluid .or. &
                                    sw(i, j, k - 1) == node_fluid .or. sw(i, j, k) == node_fluid)
            end do
          end do
        end do
      end do
      call exchange_slab_halos(grid%slab, open)
      ! What each open cell offers its z neighbours (these may be on the next rank).
      do b = 1, size(bands)
        do k = bands(b)%k_first, bands(b)%k_last
          do jj = bands(b)%j_first, bands(b)%j_last
            j = wrap(jj, ny)
            do ii = bands(b)%lo(jj, k), bands(b)%hi(jj, k)
              i = wrap(ii, nx)
              if (open(i, j, k) > 0.5_wp) then
                ibm%offer_down(i, j, k) = extrapolated(pressure(i, j, k), pressure(i, j, k + 1), open(i, j, k + 1))
                ibm%offer_up(i, j, k) = extrapolated(pressure(i, j, k), pressure(i, j, k - 1), open(i, j, k - 1))
              end if
            end do
          end do
        end do
      end do
      call exchange_slab_halos(grid%slab, ibm%offer_down, ibm%offer_up)
      do b = 1, size(bands)
        do k = bands(b)%k_first, bands(b)%k_last
          do jj = bands(b)%j_first, bands(b)%j_last
            j = wrap(jj, ny)
            do ii = bands(b)%lo(jj, k), bands(b)%hi(jj, k)
              i = wrap(ii, nx)
              if (open(i, j, k) > 0.5_wp) cycle
              total = 0
              count = 0
              do d = 1, 4
                associate (i1 => wrap(i + step_x(d), nx), j1 => wrap(j + step_y(d), ny), &
                           i2 => wrap(i + 2 * step_x(d), nx), j2 => wrap(j + 2 * step_y(d), ny))
                  if (open(i1, j1, k) > 0.5_wp) then
                    total = total + extrapolated(pressure(i1, j1, k), pressure(i2, j2, k), open(i2, j2, k))
                    count = count + 1
                  end if
                end associate
              end do
              if (open(i, j, k + 1) > 0.5_wp) then
                total = total + ibm%offer_down(i, j, k + 1)
                count = count + 1
              end if
              if (open(i, j, k - 1) > 0.5_wp) then
                total = total + ibm%offer_up(i, j, k - 1)
                count = count + 1
              end if
              if (count > 0) pressure(i, j, k) = total / count
            end do
          end do
        end do
      end do
    end associate
    call exchange_slab_halos(grid%slab, pressure)
  contains
    !> 2 p1 - p2 when the cell beyond (p2) is open, else p1.
    pure real(wp) function extrapolated(p1, p2, open2) result(value)
      real(wp), intent(in) :: p1, p2, open2
      if (open2 > 0.5_wp) then
        value = 2.0_wp * p1 - p2
      else
        value = p1
      end if
    end function extrapolated
  end subroutine ibm_extend_pressure

  !> The cells within `margin` (in each index, periodic in i and j) of the solid nodes: one band per
  !> body (its ghost and interior nodes of every component on this rank, row by row), and one for
  !> each of the neighbouring ranks' edge planes (whole rows near their solid nodes: this rank's edge
  !> cells feed their sealed cells through cell_open and the offers' halo exchange). A sealed cell's
  !> faces are solid nodes within one index of it, so it and the neighbours it reads lie in the band
  !> of a body one of its faces belongs to (or in an edge plane's band). A body spans less than half
  !> the box (immersed_geometry), so its indices unwrap about its first node.
  subroutine near_bands(ibm, grid, margin, bands)
    type(immersed_boundary_t), intent(in) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: margin
    type(cell_band_t), allocatable, intent(out) :: bands(:)
    integer, allocatable :: reference(:, :), lowest(:, :), highest(:, :), lo(:, :), hi(:, :)
    logical :: edge_j(grid%ny, 2), edge_k(2)
    integer :: c, m, b, n_bodies, nzl, pass, j, k, n_used, e
    nzl = grid%nz_local
    n_bodies = ibm%geometry%n_bodies
    ! Per body: the reference node (unwrapping), then the unwrapped index ranges, then each row's cells.
    allocate(reference(3, n_bodies), lowest(3, n_bodies), highest(3, n_bodies), bands(n_bodies + 2))
    reference = huge(1)
    lowest = huge(1)
    highest = -huge(1)
    do pass = 1, 2
      if (pass == 2) then
        do b = 1, n_bodies
          if (highest(3, b) < lowest(3, b)) cycle
          allocate(bands(b)%lo(lowest(2, b):highest(2, b), lowest(3, b):highest(3, b)), &
                   bands(b)%hi(lowest(2, b):highest(2, b), lowest(3, b):highest(3, b)))
          bands(b)%lo = huge(1)
          bands(b)%hi = -huge(1)
        end do
      end if
      do c = 1, 3
        associate (nodes => ibm%geometry%component(c))
          do m = 1, nodes%n_ghost
            call mark(nodes%ghost(m)%body, nodes%ghost(m)%node)
          end do
          do m = 1, nodes%n_interior
            call mark(nodes%interior_body(m), nodes%interior(:, m))
          end do
        end associate
      end do
    end do
    n_used = 0
    do b = 1, n_bodies
      if (highest(3, b) < lowest(3, b)) cycle
      ! Each row's cells: the solid nodes' range over the rows within the margin, widened by it.
      allocate(lo(lowest(2, b) - margin:highest(2, b) + margin, lowest(3, b) - margin:highest(3, b) + margin))
      allocate(hi, mold=lo)
      lo = huge(1)
      hi = -huge(1)
      do k = lowest(3, b), highest(3, b)
        do j = lowest(2, b), highest(2, b)
          if (bands(b)%lo(j, k) > bands(b)%hi(j, k)) cycle
          lo(j - margin:j + margin, k - margin:k + margin) = min(lo(j - margin:j + margin, k - margin:k + margin), &
                                                                 bands(b)%lo(j, k) - margin)
          hi(j - margin:j + margin, k - margin:k + margin) = max(hi(j - margin:j + margin, k - margin:k + margin), &
                                                                 bands(b)%hi(j, k) + margin)
        end do
      end do
      where (lo > hi)   ! an empty row as 1..0 (huge bounds would overflow the loop's trip count)
        lo = 1
        hi = 0
      end where
      n_used = n_used + 1
      bands(n_used)%j_first = lbound(lo, 1)
      bands(n_used)%j_last = ubound(lo, 1)
      bands(n_used)%k_first = max(1, lbound(lo, 2))
      bands(n_used)%k_last = min(nzl, ubound(lo, 2))
      associate (band => bands(n_used))
        ! (a new allocation with the rows' bounds: an assignment would rebase them to 1)
        if (allocated(band%lo)) deallocate(band%lo, band%hi)
        allocate(band%lo(band%j_first:band%j_last, band%k_first:band%k_last), &
                 band%hi(band%j_first:band%j_last, band%k_first:band%k_last))
        band%lo = lo(:, band%k_first:band%k_last)
        band%hi = hi(:, band%k_first:band%k_last)
      end associate
      deallocate(lo, hi)
    end do
    ! The neighbouring ranks' edge planes: whole rows within the margin of a row with a solid node.
    edge_j = .false.
    edge_k = .false.
    do c = 1, 3
      associate (status => ibm%geometry%component(c)%status)
        do e = 1, 2
          k = merge(0, nzl + 1, e == 1)
          if (all(status(1:grid%nx, 1:grid%ny, k) == node_fluid)) cycle
          edge_k(e) = .true.
          edge_j(:, e) = edge_j(:, e) .or. any(status(1:grid%nx, 1:grid%ny, k) /= node_fluid, dim=1)
        end do
      end associate
    end do
    do e = 1, 2
      if (.not. edge_k(e)) cycle
      n_used = n_used + 1
      bands(n_used)%j_first = 1
      bands(n_used)%j_last = grid%ny
      bands(n_used)%k_first = merge(1, max(1, nzl - margin), e == 1)
      bands(n_used)%k_last = merge(min(nzl, 1 + margin), nzl, e == 1)
      ! (the slot may still hold the unwrapped rows of a body moved down past a body without nodes)
      if (allocated(bands(n_used)%lo)) deallocate(bands(n_used)%lo, bands(n_used)%hi)
      allocate(bands(n_used)%lo(1:grid%ny, bands(n_used)%k_first:bands(n_used)%k_last), &
               bands(n_used)%hi(1:grid%ny, bands(n_used)%k_first:bands(n_used)%k_last))
      do j = 1, grid%ny
        ! A row of the plane within the margin (periodic in j) of a row with a solid node.
        if (any(edge_j([(wrap(j + m, grid%ny), m = -margin, margin)], e))) then
          bands(n_used)%lo(j, :) = 1
          bands(n_used)%hi(j, :) = grid%nx
        else
          bands(n_used)%lo(j, :) = 1
          bands(n_used)%hi(j, :) = 0
        end if
      end do
    end do
    bands = bands(1:n_used)
  contains
    !> Pass 1: the reference and the unwrapped ranges of j and k; pass 2: each row's range of i.
    subroutine mark(body, node)
      integer, intent(in) :: body, node(3)
      integer :: unwrapped(3), size_of(3)
      if (reference(1, body) == huge(1)) reference(:, body) = node
      size_of = [grid%nx, grid%ny, huge(1) / 4]
      ! The index nearest the reference among the node's periodic copies (k is local: not wrapped).
      unwrapped(1:2) = reference(1:2, body) + modulo(node(1:2) - reference(1:2, body) + size_of(1:2) / 2, size_of(1:2)) &
                       - size_of(1:2) / 2
      unwrapped(3) = node(3)
      if (pass == 1) then
        lowest(:, body) = min(lowest(:, body), unwrapped)
        highest(:, body) = max(highest(:, body), unwrapped)
      else
        bands(body)%lo(unwrapped(2), unwrapped(3)) = min(bands(body)%lo(unwrapped(2), unwrapped(3)), unwrapped(1))
        bands(body)%hi(unwrapped(2), unwrapped(3)) = max(bands(body)%hi(unwrapped(2), unwrapped(3)), unwrapped(1))
      end if
    end subroutine mark
  end subroutine near_bands
end module immersed_pressure_extension
