!> The particle-pair scenes without a grid: fluid = 'none' (vacuum) or 'stokes' (resistance tensors).
module pair_scene
  use agglo_config, only: agglo_config_t
  use logger, only: log_line
  implicit none
  private
  public :: run_pair_scene

contains

  subroutine run_pair_scene(cfg)
    type(agglo_config_t), intent(in) :: cfg
    call log_line('pair scene: '//trim(cfg%run%name)//' (not built yet)')
  end subroutine run_pair_scene
end module pair_scene
