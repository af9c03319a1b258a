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
  use immersed_boundary, only: immersed_boundary_t
  implicit none
  private
  public :: ibm_extend_pressure

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
    integer :: i, j, k, nx, ny, nzl, d, count
    real(wp) :: total
    integer, parameter :: step_x(4) = [1, -1, 0, 0], step_y(4) = [0, 0, 1, -1]
    logical, allocatable :: near_i(:), near_j(:), near_k(:)
    nx = grid%nx; ny = grid%ny; nzl = grid%nz_local
    if (.not. allocated(ibm%cell_open)) then
      allocate(ibm%cell_open, ibm%offer_down, ibm%offer_up, mold=pressure)
      ibm%cell_open = 1; ibm%offer_down = 0; ibm%offer_up = 0
    end if
    ! Only cells within 3 of a solid node are visited (a tensor product of index ranges, like the
    ! classification's); cell_open stays 1 elsewhere: a body moves less than a cell per step, so
    ! the cells it sealed before lie in the new range.
    call near_ranges(ibm, grid, 3, near_i, near_j, near_k)
    associate (su => ibm%geometry%component(1)%status, sv => ibm%geometry%component(2)%status, &
               sw => ibm%geometry%component(3)%status, open => ibm%cell_open)
      ! A cell is open when one of its six faces (u(i-1), u(i), v(j-1), v(j), w(k-1), w(k)) is a fluid node.
      do k = 1, nzl
        if (.not. near_k(k)) cycle
        do j = 1, ny
          if (.not. near_j(j)) cycle
          do i = 1, nx
            if (.not. near_i(i)) cycle
            open(i, j, k) = merge(1.0_wp, 0.0_wp, su(i - 1, j, k) == node_fluid .or. su(i, j, k) == node_fluid .or. &
                                  sv(i, j - 1, k) == node_fluid .or. sv(i, j, k) == node_fluid .or. &
                                  sw(i, j, k - 1) == node_fluid .or. sw(i, j, k) == node_fluid)
          end do
        end do
      end do
      call exchange_slab_halos(grid%slab, open)
      ! What each open cell offers its z neighbours (these may be on the next rank).
      do k = 1, nzl
        if (.not. near_k(k)) cycle
        do j = 1, ny
          if (.not. near_j(j)) cycle
          do i = 1, nx
            if (.not. near_i(i)) cycle
            if (open(i, j, k) > 0.5_wp) then
              ibm%offer_down(i, j, k) = extrapolated(pressure(i, j, k), pressure(i, j, k + 1), open(i, j, k + 1))
              ibm%offer_up(i, j, k) = extrapolated(pressure(i, j, k), pressure(i, j, k - 1), open(i, j, k - 1))
            end if
          end do
        end do
      end do
      call exchange_slab_halos(grid%slab, ibm%offer_down, ibm%offer_up)
      do k = 1, nzl
        if (.not. near_k(k)) cycle
        do j = 1, ny
          if (.not. near_j(j)) cycle
          do i = 1, nx
            if (.not. near_i(i)) cycle
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
    pure integer function wrap(i, n)
      integer, intent(in) :: i, n
      wrap = modulo(i - 1, n) + 1
    end function wrap
  end subroutine ibm_extend_pressure

  !> The i, j (global) and k (local, 1..nz_local) indices within `margin` of a ghost or interior
  !> node of any component on this rank (periodic in i and j).
  subroutine near_ranges(ibm, grid, margin, near_i, near_j, near_k)
    type(immersed_boundary_t), intent(in) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: margin
    logical, allocatable, intent(out) :: near_i(:), near_j(:), near_k(:)
    logical, allocatable :: solid_i(:), solid_j(:), solid_k(:)
    integer :: c, m, s
    allocate(solid_i(grid%nx), solid_j(grid%ny), solid_k(grid%nz_local))
    solid_i = .false.; solid_j = .false.; solid_k = .false.
    do c = 1, 3
      associate (nodes => ibm%geometry%component(c))
        do m = 1, nodes%n_ghost
          call mark(nodes%ghost(m)%node)
        end do
        do m = 1, nodes%n_interior
          call mark(nodes%interior(:, m))
        end do
        ! Solid nodes of the neighbouring ranks' edge planes: this rank's edge cells feed their
        ! sealed cells (cell_open, offers through the halo exchange).
        call mark_plane(nodes%status(1:grid%nx, 1:grid%ny, 0), 1)
        call mark_plane(nodes%status(1:grid%nx, 1:grid%ny, grid%nz_local + 1), grid%nz_local)
      end associate
    end do
    allocate(near_i(grid%nx), near_j(grid%ny), near_k(grid%nz_local))
    near_i = solid_i; near_j = solid_j; near_k = solid_k
    do s = 1, margin
      near_i = near_i .or. cshift(solid_i, s) .or. cshift(solid_i, -s)
      near_j = near_j .or. cshift(solid_j, s) .or. cshift(solid_j, -s)
      near_k(1 + s:) = near_k(1 + s:) .or. solid_k(:grid%nz_local - s)
      near_k(:grid%nz_local - s) = near_k(:grid%nz_local - s) .or. solid_k(1 + s:)
    end do
  contains
    subroutine mark(node)
      integer, intent(in) :: node(3)
      solid_i(node(1)) = .true.
      solid_j(node(2)) = .true.
      solid_k(node(3)) = .true.
    end subroutine mark
    subroutine mark_plane(status, k)
      integer(int8), intent(in) :: status(:, :)
      integer, intent(in) :: k
      if (all(status == node_fluid)) return
      solid_i = solid_i .or. any(status /= node_fluid, dim=2)
      solid_j = solid_j .or. any(status /= node_fluid, dim=1)
      solid_k(k) = .true.
    end subroutine mark_plane
  end subroutine near_ranges
end module immersed_pressure_extension
