!> The graph of bonds between N bodies: its connected components by union-find and its adjacency
!> lists (docs/theory.md, "Agglomerates"). Bodies are the vertices 1..N, a bond (first, second) an
!> undirected edge; a body without bonds is a component of its own.
!>
!> Union-find (disjoint-set forest; Tarjan 1975, J. ACM 22, 215): every set is a tree whose root
!> names it; union by size hangs the smaller tree under the root of the larger one, and every find
!> points the nodes on its path straight at the root (path compression). Together they cost
!> O(alpha(N)) amortised per operation, alpha the inverse Ackermann function (at most 4 for any N
!> that fits in memory), so the components of N bodies and B bonds cost O(N + B alpha(N)).
!> The forest is two plain integer arrays owned by the caller; nothing is kept between calls.
module bond_graph
  implicit none
  private
  public :: bond_t, union_find_init, union_find_root, union_find_unite, component_labels, adjacency_t, adjacency_build

  !> A bond: body second, at its image position(second) + image * box_length (box_length the
  !> periods, elementwise), is bonded to body first. The graph algorithms read first and second;
  !> the image is the agglomerate analysis's (module agglomerates).
  type :: bond_t
    integer :: first = 0
    integer :: second = 0
    integer :: image(3) = 0    !< periods per direction (0 in an unbounded direction)
  end type bond_t

  !> Adjacency lists in compressed rows: the bonds of body i are the entries start(i) .. start(i+1) - 1
  !> of neighbour (the other body) and bond (the bond's index in the caller's list). Every bond
  !> appears twice, once from each end; within a body's row in the order of the bond list.
  type :: adjacency_t
    integer, allocatable :: start(:)       !< (N + 1)
    integer, allocatable :: neighbour(:)   !< (2 B)
    integer, allocatable :: bond(:)        !< (2 B)
  end type adjacency_t

contains

  !> N singletons: every body its own root, every set of size 1.
  pure subroutine union_find_init(parent, set_size)
    integer, intent(out) :: parent(:), set_size(:)
    integer :: i
    do i = 1, size(parent)
      parent(i) = i
    end do
    set_size = 1
  end subroutine union_find_init

  !> The root of body i's set; every node on the way is then pointed at the root (path compression,
  !> two passes, iterative so that a long chain cannot overflow the stack).
  pure subroutine union_find_root(parent, i, root)
    integer, intent(inout) :: parent(:)
    integer, intent(in) :: i
    integer, intent(out) :: root
    integer :: node, next
    root = i
    do while (parent(root) /= root)
      root = parent(root)
    end do
    node = i
    do while (parent(node) /= root)
      next = parent(node)
      parent(node) = root
      node = next
    end do
  end subroutine union_find_root

  !> Join the sets of bodies i and j (union by size; ties hang j's root under i's).
  pure subroutine union_find_unite(parent, set_size, i, j)
    integer, intent(inout) :: parent(:), set_size(:)
    integer, intent(in) :: i, j
    integer :: root_i, root_j
    call union_find_root(parent, i, root_i)
    call union_find_root(parent, j, root_j)
    if (root_i == root_j) return
    if (set_size(root_i) < set_size(root_j)) then
      parent(root_i) = root_j
      set_size(root_j) = set_size(root_j) + set_size(root_i)
    else
      parent(root_j) = root_i
      set_size(root_i) = set_size(root_i) + set_size(root_j)
    end if
  end subroutine union_find_unite

  !> Connected components of the graph of n bodies and the bonds, by union-find.
  !> labels(i) in 1..components, numbered in the order of each component's smallest body, so the
  !> labelling depends on the graph alone, not on the order of the bonds or the shape of the forest.
  !> Indices must lie in 1..n (the caller checks).
  pure subroutine component_labels(n, bonds, labels, components)
    integer, intent(in) :: n
    type(bond_t), intent(in) :: bonds(:)
    integer, intent(out) :: labels(n), components
    integer, allocatable :: parent(:), set_size(:), label_of_root(:)
    integer :: b, i, root
    allocate(parent(n), set_size(n), label_of_root(n))
    call union_find_init(parent, set_size)
    do b = 1, size(bonds)
      call union_find_unite(parent, set_size, bonds(b)%first, bonds(b)%second)
    end do
    label_of_root = 0
    components = 0
    do i = 1, n
      call union_find_root(parent, i, root)
      if (label_of_root(root) == 0) then
        components = components + 1
        label_of_root(root) = components
      end if
      labels(i) = label_of_root(root)
    end do
  end subroutine component_labels

  !> Adjacency lists of n bodies from the bonds (indices in 1..n), by a counting sort: O(n + B),
  !> three passes, no search.
  pure subroutine adjacency_build(n, bonds, adjacency)
    integer, intent(in) :: n
    type(bond_t), intent(in) :: bonds(:)
    type(adjacency_t), intent(out) :: adjacency
    integer, allocatable :: fill(:)
    integer :: b, i, k
    allocate(fill(n), adjacency%start(n + 1), adjacency%neighbour(2 * size(bonds)), adjacency%bond(2 * size(bonds)))
    fill = 0
    do b = 1, size(bonds)
      fill(bonds(b)%first) = fill(bonds(b)%first) + 1
      fill(bonds(b)%second) = fill(bonds(b)%second) + 1
    end do
    adjacency%start(1) = 1
    do i = 1, n
      adjacency%start(i + 1) = adjacency%start(i) + fill(i)
    end do
    fill = adjacency%start(1:n)
    do b = 1, size(bonds)
      associate (i1 => bonds(b)%first, i2 => bonds(b)%second)
        k = fill(i1)
        adjacency%neighbour(k) = i2
        adjacency%bond(k) = b
        fill(i1) = k + 1
        k = fill(i2)
        adjacency%neighbour(k) = i1
        adjacency%bond(k) = b
        fill(i2) = k + 1
      end associate
    end do
  end subroutine adjacency_build

end module bond_graph
