!> The resolved scene: DNS of the periodic box (fluid only until the immersed boundary lands).
module resolved_scene
  use agglo_config, only: agglo_config_t
  use logger, only: log_line
  implicit none
  private
  public :: run_resolved_scene

contains

  subroutine run_resolved_scene(cfg)
    type(agglo_config_t), intent(in) :: cfg
    call log_line('resolved scene: '//trim(cfg%run%name)//' (solver not built yet)')
  end subroutine run_resolved_scene
end module resolved_scene
