"""myriad's panel in Render Properties, and Blender's own panels (dimensions, output,
camera, lights, world, materials, passes) shown for myriad too, as Cycles shows them."""

import bpy

from .engine import MyriadRenderEngine

ENGINE = MyriadRenderEngine.bl_idname

# Blender's panels that describe what myriad renders as well. Looked up by name, so that a
# panel a Blender version renames or drops is simply skipped (the add-on still loads).
SHARED_PANELS = [
    "RENDER_PT_format", "RENDER_PT_frame_range", "RENDER_PT_output", "RENDER_PT_encoding",
    "RENDER_PT_color_management", "RENDER_PT_post_processing",
    "DATA_PT_context_camera", "DATA_PT_camera", "DATA_PT_lens", "DATA_PT_camera_dof",
    "DATA_PT_camera_dof_aperture", "DATA_PT_camera_safe_areas",
    "DATA_PT_context_light", "DATA_PT_light", "DATA_PT_EEVEE_light", "DATA_PT_EEVEE_light_distance",
    "DATA_PT_spot", "DATA_PT_area",
    "WORLD_PT_context_world", "EEVEE_WORLD_PT_surface",
    "MATERIAL_PT_context_material", "EEVEE_MATERIAL_PT_context_material", "EEVEE_MATERIAL_PT_surface",
    "EEVEE_MATERIAL_PT_volume", "MATERIAL_PT_preview",
    "VIEWLAYER_PT_layer", "VIEWLAYER_PT_layer_passes", "VIEWLAYER_PT_layer_passes_data",
]  # fmt: skip


class MYRIAD_PT_render(bpy.types.Panel):
    """The render settings."""

    bl_label = "myriad"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    COMPAT_ENGINES = {ENGINE}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        settings = context.scene.myriad
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        col = layout.column()
        col.prop(settings, "samples")
        col.prop(settings, "time")
        col.prop(settings, "sampler")
        col.prop(settings, "max_depth")
        col.prop(settings, "clamp_direct")
        col.prop(settings, "clamp_indirect")
        col.prop(settings, "guiding")
        col.prop(settings, "caustics")
        col.prop(settings, "seed")
        layout.prop(settings, "binary")


def _shared_panels():
    return [p for p in (getattr(bpy.types, name, None) for name in SHARED_PANELS) if p is not None]


def register():
    bpy.utils.register_class(MYRIAD_PT_render)
    for panel in _shared_panels():
        if hasattr(panel, "COMPAT_ENGINES"):
            panel.COMPAT_ENGINES.add(ENGINE)


def unregister():
    for panel in _shared_panels():
        if hasattr(panel, "COMPAT_ENGINES"):
            panel.COMPAT_ENGINES.discard(ENGINE)
    bpy.utils.unregister_class(MYRIAD_PT_render)
