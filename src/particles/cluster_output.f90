!> clusters.h5: the agglomerates of a suspension over time (docs/outputs.md, "clusters.h5"), one row
!> per output time, written by rank 0 alone through a serial HDF5 handle (every routine may be called
!> on every rank; the others return at once, after dropping the events they were handed, so every
!> rank's tracker stays alike). Lengths m, times s, angles rad, speeds m/s; T rows, N bodies.
!> Root attributes: bodies (N), box_length (3), species_names (S), bond_rule (text).
!>   /time (T); /summary/{clusters, bonds, mean_size_number, mean_size_weight, largest,
!>   mean_coordination, percolating} (T); /body/{cluster, coordination} (N, T) (h5py (T, N));
!>   /cluster/row_start (T + 1) and /cluster/{size, radius_of_gyration, radius_of_gyration_centres,
!>   percolating} (sum K), gyration_eigenvalues and centre (3, sum K); /bond/row_start (T + 1),
!>   /bond/pair (2, sum B), /bond/psi (sum B); /events/{time, kind, normal_speed, gap} (E),
!>   /events/{pair, theta, phi} (2, E); /collisions/species_pairs (2, P), /collisions/count (P, T)
!>   and /collisions/volume (scalar, m^3).
!> Every dataset but the attributes, species_pairs and volume is extendible: a restarted run cuts
!> them back to the counts its checkpoint recorded (cluster_output_continue) and appends.
module cluster_output
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use parallel_env, only: is_root
  use hdf5_files, only: h5_file_t, h5_create, h5_open, h5_close, h5_flush
  use hdf5_datasets, only: h5_write_array
  use hdf5_series, only: h5_append, h5_truncate
  use hdf5_attributes, only: h5_write_attribute
  use particle_system, only: particle_system_t
  use agglomerates, only: agglomerates_t, agglomerates_analyse
  use agglomerate_tracking, only: agglomerate_tracker_t, bond_event_t, agglomerate_take_events, agglomerate_bonds, &
                                  species_pairs
  implicit none
  private
  public :: cluster_output_t, cluster_output_open, cluster_output_continue, cluster_output_row, cluster_output_flush, &
            cluster_output_counts, cluster_output_close, cluster_bond_rule

  character(len=*), parameter :: cluster_bond_rule = 'bound in the DLVO well: E = mu v_n^2/2 + U(h) < U_b, h <= h_r'

  !> Datasets with a row per output time, per cluster entry, per bond entry and per event.
  character(len=*), parameter :: row_sets(10) = [character(len=40) :: 'time', 'summary/clusters', 'summary/bonds', &
      'summary/mean_size_number', 'summary/mean_size_weight', 'summary/largest', 'summary/mean_coordination', &
      'summary/percolating', 'body/cluster', 'body/coordination']
  character(len=*), parameter :: cluster_sets(6) = [character(len=40) :: 'cluster/size', 'cluster/radius_of_gyration', &
      'cluster/radius_of_gyration_centres', 'cluster/gyration_eigenvalues', 'cluster/centre', 'cluster/percolating']
  character(len=*), parameter :: bond_sets(2) = [character(len=40) :: 'bond/pair', 'bond/psi']
  character(len=*), parameter :: event_sets(7) = [character(len=40) :: 'events/time', 'events/kind', 'events/pair', &
      'events/theta', 'events/phi', 'events/normal_speed', 'events/gap']

  !> An open clusters.h5 (only rank 0's copy is active). counts: rows, cluster entries, bond entries
  !> and events written; before_last: the first three before the last row.
  type :: cluster_output_t
    type(h5_file_t) :: file
    logical :: active = .false.
    integer(i8) :: counts(4) = 0_i8
    integer(i8) :: before_last(3) = 0_i8
  end type cluster_output_t

contains

  !> Create clusters.h5 at path (rank 0): the attributes, the fixed datasets and every series empty.
  subroutine cluster_output_open(out, path, system, tracker, species_names)
    type(cluster_output_t), intent(out) :: out
    character(len=*), intent(in) :: path
    type(particle_system_t), intent(in) :: system
    type(agglomerate_tracker_t), intent(in) :: tracker
    character(len=*), intent(in) :: species_names(:)
    integer :: i
    out%active = is_root()
    if (.not. out%active) return
    call h5_create(out%file, path, serial=.true.)
    call h5_write_attribute(out%file, '/', 'bodies', system%n)
    call h5_write_attribute(out%file, '/', 'box_length', system%box_length)
    call h5_write_attribute(out%file, '/', 'species_names', species_names)
    call h5_write_attribute(out%file, '/', 'bond_rule', cluster_bond_rule)
    call h5_write_array(out%file, 'collisions/species_pairs', species_pairs(tracker%species))
    call h5_write_array(out%file, 'collisions/volume', product(system%box_length))
    ! Every series exists from the start (an empty table still has its datasets).
    do i = 1, size(row_sets)
      if (row_sets(i)(1:5) == 'body/') then
        call h5_append(out%file, trim(row_sets(i)), reshape([integer ::], [system%n, 0]))
      else if (any(row_sets(i) == [character(len=40) :: 'time', 'summary/mean_size_number', &
                                   'summary/mean_size_weight', 'summary/mean_coordination'])) then
        call h5_append(out%file, trim(row_sets(i)), [real(wp) ::])
      else
        call h5_append(out%file, trim(row_sets(i)), [integer ::])
      end if
    end do
    call h5_append(out%file, 'collisions/count', reshape([integer ::], [size(tracker%collisions), 0]))
    call h5_append(out%file, 'cluster/row_start', [0])
    call h5_append(out%file, 'bond/row_start', [0])
    call h5_append(out%file, 'cluster/size', [integer ::])
    call h5_append(out%file, 'cluster/radius_of_gyration', [real(wp) ::])
    call h5_append(out%file, 'cluster/radius_of_gyration_centres', [real(wp) ::])
    call h5_append(out%file, 'cluster/gyration_eigenvalues', reshape([real(wp) ::], [3, 0]))
    call h5_append(out%file, 'cluster/centre', reshape([real(wp) ::], [3, 0]))
    call h5_append(out%file, 'cluster/percolating', [integer ::])
    call h5_append(out%file, 'bond/pair', reshape([integer ::], [2, 0]))
    call h5_append(out%file, 'bond/psi', [real(wp) ::])
    call write_events(out, [bond_event_t ::])
  end subroutine cluster_output_open

  !> Continue the clusters.h5 at path of an interrupted or finished run (rank 0) from the counts its
  !> checkpoint recorded (cluster_output_counts): later rows are dropped, new rows append.
  subroutine cluster_output_continue(out, path, counts)
    type(cluster_output_t), intent(out) :: out
    character(len=*), intent(in) :: path
    integer(i8), intent(in) :: counts(4)
    integer :: i
    out%active = is_root()
    out%counts = counts
    out%before_last = counts(1:3)
    if (.not. out%active) return
    call h5_open(out%file, path, writable=.true., serial=.true.)
    do i = 1, size(row_sets)
      call h5_truncate(out%file, trim(row_sets(i)), int(counts(1)))
    end do
    call h5_truncate(out%file, 'collisions/count', int(counts(1)))
    call h5_truncate(out%file, 'cluster/row_start', int(counts(1)) + 1)
    call h5_truncate(out%file, 'bond/row_start', int(counts(1)) + 1)
    do i = 1, size(cluster_sets)
      call h5_truncate(out%file, trim(cluster_sets(i)), int(counts(2)))
    end do
    do i = 1, size(bond_sets)
      call h5_truncate(out%file, trim(bond_sets(i)), int(counts(3)))
    end do
    do i = 1, size(event_sets)
      call h5_truncate(out%file, trim(event_sets(i)), int(counts(4)))
    end do
  end subroutine cluster_output_continue

  !> One row at time (s): the events waiting in the tracker, then the clusters of the current bonds.
  !> Returns the agglomerates of the row when asked (every rank computes them alike).
  subroutine cluster_output_row(out, time, system, tracker, clusters)
    type(cluster_output_t), intent(inout) :: out
    real(wp), intent(in) :: time
    type(particle_system_t), intent(in) :: system
    type(agglomerate_tracker_t), intent(inout) :: tracker
    type(agglomerates_t), intent(out), optional :: clusters
    type(agglomerates_t) :: result
    type(bond_event_t), allocatable :: events(:)
    integer :: b
    call agglomerate_take_events(tracker, events)
    call write_events(out, events)
    if (.not. (out%active .or. present(clusters))) return
    call agglomerates_analyse(system%shapes, system%bodies, system%box_length, agglomerate_bonds(tracker), result)
    if (present(clusters)) clusters = result
    if (.not. out%active) return
    associate (file => out%file, k => result%clusters)
      call h5_append(file, 'time', [time])
      call h5_append(file, 'summary/clusters', [k])
      call h5_append(file, 'summary/bonds', [result%bonds])
      call h5_append(file, 'summary/mean_size_number', [result%mean_size_number])
      call h5_append(file, 'summary/mean_size_weight', [result%mean_size_weight])
      call h5_append(file, 'summary/largest', [result%largest])
      call h5_append(file, 'summary/mean_coordination', [result%mean_coordination])
      call h5_append(file, 'summary/percolating', [result%percolating_clusters])
      call h5_append(file, 'body/cluster', reshape(result%cluster_of, [system%n, 1]))
      call h5_append(file, 'body/coordination', reshape(result%coordination, [system%n, 1]))
      call h5_append(file, 'collisions/count', reshape(int(tracker%collisions), [size(tracker%collisions), 1]))
      call h5_append(file, 'cluster/size', result%cluster_size)
      call h5_append(file, 'cluster/radius_of_gyration', result%radius_of_gyration)
      call h5_append(file, 'cluster/radius_of_gyration_centres', result%radius_of_gyration_centres)
      call h5_append(file, 'cluster/gyration_eigenvalues', result%gyration_eigenvalues)
      call h5_append(file, 'cluster/centre', result%centre_of_mass)
      call h5_append(file, 'cluster/percolating', merge(1, 0, result%percolating))
      call h5_append(file, 'bond/pair', reshape([(tracker%bonds(b)%first, tracker%bonds(b)%second, &
                                                  b = 1, size(tracker%bonds))], [2, size(tracker%bonds)]))
      call h5_append(file, 'bond/psi', result%psi)
      out%before_last = out%counts(1:3)
      out%counts(1:3) = out%counts(1:3) + [1_i8, int(k, i8), int(result%bonds, i8)]
      call h5_append(file, 'cluster/row_start', [int(out%counts(2))])
      call h5_append(file, 'bond/row_start', [int(out%counts(3))])
    end associate
  end subroutine cluster_output_row

  subroutine write_events(out, events)
    type(cluster_output_t), intent(inout) :: out
    type(bond_event_t), intent(in) :: events(:)
    integer :: e
    if (.not. out%active) return
    call h5_append(out%file, 'events/time', events%time)
    call h5_append(out%file, 'events/kind', events%kind)
    call h5_append(out%file, 'events/pair', reshape([(events(e)%pair, e = 1, size(events))], [2, size(events)]))
    call h5_append(out%file, 'events/theta', reshape([(events(e)%theta, e = 1, size(events))], [2, size(events)]))
    call h5_append(out%file, 'events/phi', reshape([(events(e)%phi, e = 1, size(events))], [2, size(events)]))
    call h5_append(out%file, 'events/normal_speed', events%normal_speed)
    call h5_append(out%file, 'events/gap', events%gap)
    out%counts(4) = out%counts(4) + size(events)
  end subroutine write_events

  !> Write the waiting events and push the file to disk (before a checkpoint records the counts).
  subroutine cluster_output_flush(out, tracker)
    type(cluster_output_t), intent(inout) :: out
    type(agglomerate_tracker_t), intent(inout) :: tracker
    type(bond_event_t), allocatable :: events(:)
    call agglomerate_take_events(tracker, events)
    call write_events(out, events)
    if (out%active) call h5_flush(out%file)
  end subroutine cluster_output_flush

  !> The counts a checkpoint records (rank 0's; 0 elsewhere): rows, cluster and bond entries, events;
  !> without_last_row: those before the last row (a finished run's extra last row is not kept).
  function cluster_output_counts(out, without_last_row) result(counts)
    type(cluster_output_t), intent(in) :: out
    logical, intent(in) :: without_last_row
    integer(i8) :: counts(4)
    counts = out%counts
    if (without_last_row) counts(1:3) = out%before_last
  end function cluster_output_counts

  subroutine cluster_output_close(out, tracker)
    type(cluster_output_t), intent(inout) :: out
    type(agglomerate_tracker_t), intent(inout) :: tracker
    call cluster_output_flush(out, tracker)
    if (.not. out%active) return
    call h5_close(out%file)
    out%active = .false.
  end subroutine cluster_output_close
end module cluster_output
