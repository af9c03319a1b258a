!> What the log reports on the immersed boundary: the nodes that change status as the bodies move
!> and the load jumps they cause (docs/theory.md, "Immersed boundary: moving bodies"), the largest
!> cell divergence left after the imposition (non-zero only in the cut cells), and the ghost rows
!> whose image point was moved back or saturated because another body is near (immersed_geometry).
module immersed_diagnostics
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM, MPI_INTEGER
  use agglo_kinds, only: wp
  use parallel_env, only: world, global_max
  use fluid_grid, only: fluid_grid_t
  use immersed_geometry, only: fallback_count, saturated_count
  use immersed_boundary, only: immersed_boundary_t, status_change_report_t
  implicit none
  private
  public :: record_load_jump, status_change_summary, cell_divergence_max, ibm_fallback_rows

contains

  !> The load jump of the step (status_change_report_t), counted apart for the steps in which
  !> nodes changed status; the force history moves on.
  subroutine record_load_jump(changes, history, force)
    type(status_change_report_t), intent(inout) :: changes
    real(wp), allocatable, intent(inout) :: history(:, :, :)   !< (3, n, 2): F^n, F^{n-1}
    real(wp), intent(in) :: force(:, :)
    integer :: n
    real(wp) :: jump, largest, scale
    changes%steps = changes%steps + 1
    if (changes%uncovered + changes%covered > 0) changes%steps_with_changes = changes%steps_with_changes + 1
    if (.not. allocated(history)) then
      allocate(history(3, size(force, 2), 2))
      history = 0
    end if
    changes%last_jump = 0
    if (changes%steps > changes%settling_steps) then
      largest = 0
      jump = 0
      do n = 1, size(force, 2)
        largest = max(largest, norm2(force(:, n)))
        jump = max(jump, norm2(force(:, n) - 2.0_wp * history(:, n, 1) + history(:, n, 2)))
      end do
      changes%mean_square = changes%mean_square + largest**2
      scale = sqrt(changes%mean_square / (changes%steps - changes%settling_steps))
      if (changes%steps > changes%settling_steps + 2 .and. scale > 0.0_wp) then
        changes%last_jump = jump / scale
        ! A spike at step n shows in the jumps of steps n and n + 1.
        if (changes%uncovered + changes%covered > 0 .or. changes%changed_before) then
          if (changes%last_jump > changes%largest_jump_changes) changes%step_of_largest = changes%steps
          changes%largest_jump_changes = max(changes%largest_jump_changes, changes%last_jump)
        else
          changes%largest_jump_steady = max(changes%largest_jump_steady, changes%last_jump)
        end if
      end if
    end if
    history(:, :, 2) = history(:, :, 1)
    history(:, :, 1) = force
    changes%changed_before = changes%uncovered + changes%covered > 0
  end subroutine record_load_jump

  !> One log line on the status changes of a run and the load jumps (status_change_report_t).
  function status_change_summary(changes) result(line)
    type(status_change_report_t), intent(in) :: changes
    character(len=:), allocatable :: line
    character(len=320) :: text
    write(text, '(a,i0,a,i0,a,i0,a,i0,a,es9.2,a,i0,a,es9.2,a)') 'immersed boundary: status changes: ', &
        changes%total_uncovered, ' nodes uncovered and ', changes%total_covered, ' covered in ', &
        changes%steps_with_changes, ' of ', changes%steps, ' steps; largest load jump |F(n+1) - 2 F(n) + F(n-1)| ', &
        changes%largest_jump_changes, ' of the rms load at a status change (step ', changes%step_of_largest, &
        '), ', changes%largest_jump_steady, ' at other steps'
    line = trim(text)
  end function status_change_summary

  !> Ghost rows over all ranks whose image point was moved back because another body is near
  !> (fallback rows) and, among them, the saturated Couette rows (immersed_geometry), in one
  !> reduction (collective).
  subroutine ibm_fallback_rows(ibm, fallbacks, saturated)
    type(immersed_boundary_t), intent(in) :: ibm
    integer, intent(out) :: fallbacks, saturated
    integer :: counts(2)
    counts = [fallback_count(ibm%geometry), saturated_count(ibm%geometry)]
    call MPI_Allreduce(MPI_IN_PLACE, counts, 2, MPI_INTEGER, MPI_SUM, world)
    fallbacks = counts(1)
    saturated = counts(2)
  end subroutine ibm_fallback_rows

  !> Largest |div u| (1/s) over this rank's cells and over all ranks (collective): after the
  !> re-imposition it is non-zero only in the cut cells, whose faces carry fictitious ghost values.
  function cell_divergence_max(grid, u, v, w) result(largest)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp) :: largest
    integer :: i, j, k
    largest = 0
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          largest = max(largest, abs((u(i, j, k) - u(i - 1, j, k)) / grid%dx + (v(i, j, k) - v(i, j - 1, k)) / grid%dy &
                                     + (w(i, j, k) - w(i, j, k - 1)) / grid%dz))
        end do
      end do
    end do
    largest = global_max(largest)
  end function cell_divergence_max
end module immersed_diagnostics
