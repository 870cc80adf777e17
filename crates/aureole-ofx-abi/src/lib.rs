//! The part of the OpenFX 1.4 C interface aureole uses, written from the
//! specification's headers (`ofxCore.h`, `ofxProperty.h`, `ofxParam.h`,
//! `ofxImageEffect.h`, `ofxMemory.h`, `ofxMultiThread.h`, `ofxMessage.h`):
//! the structs a host and a plugin hand each other and the names they
//! agree on. The plugin (`aureole-ofx`) and the test host
//! (`aureole-ofx-host`) both use these definitions, so the two cannot
//! drift apart, and the host links none of the plugin's code.

use std::ffi::{c_char, c_double, c_int, c_uint, c_void, CStr};

/// A status: 0 for success, the codes below otherwise.
pub type OfxStatus = c_int;
/// Every handle is a blind pointer to the host's object.
pub type Handle = *mut c_void;
pub type OfxPropertySetHandle = Handle;
pub type OfxImageEffectHandle = Handle;
pub type OfxImageClipHandle = Handle;
pub type OfxParamSetHandle = Handle;
pub type OfxParamHandle = Handle;
pub type OfxImageMemoryHandle = Handle;
pub type OfxMutexHandle = Handle;
pub type OfxTime = c_double;

pub const STAT_OK: OfxStatus = 0;
pub const STAT_FAILED: OfxStatus = 1;
pub const STAT_ERR_FATAL: OfxStatus = 2;
pub const STAT_ERR_UNKNOWN: OfxStatus = 3;
pub const STAT_ERR_MISSING_HOST_FEATURE: OfxStatus = 4;
pub const STAT_ERR_UNSUPPORTED: OfxStatus = 5;
pub const STAT_ERR_EXISTS: OfxStatus = 6;
pub const STAT_ERR_FORMAT: OfxStatus = 7;
pub const STAT_ERR_MEMORY: OfxStatus = 8;
pub const STAT_ERR_BAD_HANDLE: OfxStatus = 9;
pub const STAT_ERR_BAD_INDEX: OfxStatus = 10;
pub const STAT_ERR_VALUE: OfxStatus = 11;
pub const STAT_REPLY_DEFAULT: OfxStatus = 14;
/// `kOfxStatErrImageFormat`: the image effect API's own code.
pub const STAT_ERR_IMAGE_FORMAT: OfxStatus = 1000;

/// `OfxRectI`: x1 ≤ x < x2, y1 ≤ y < y2, y upwards.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct OfxRectI {
    pub x1: c_int,
    pub y1: c_int,
    pub x2: c_int,
    pub y2: c_int,
}

/// `OfxRectD`, in canonical coordinates.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OfxRectD {
    pub x1: c_double,
    pub y1: c_double,
    pub x2: c_double,
    pub y2: c_double,
}

/// `OfxRangeD`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OfxRangeD {
    pub min: c_double,
    pub max: c_double,
}

/// `OfxHost`: the host's property set and its suite fetcher.
#[repr(C)]
pub struct OfxHost {
    pub host: OfxPropertySetHandle,
    pub fetch_suite: unsafe extern "C" fn(
        host: OfxPropertySetHandle,
        name: *const c_char,
        version: c_int,
    ) -> *const c_void,
}

/// A plugin's entry point: an action on a handle with its arguments.
pub type MainEntry = unsafe extern "C" fn(
    action: *const c_char,
    handle: *const c_void,
    in_args: OfxPropertySetHandle,
    out_args: OfxPropertySetHandle,
) -> OfxStatus;

/// `OfxPlugin`: what `OfxGetPlugin` returns.
#[repr(C)]
pub struct OfxPlugin {
    pub plugin_api: *const c_char,
    pub api_version: c_int,
    pub plugin_identifier: *const c_char,
    pub plugin_version_major: c_uint,
    pub plugin_version_minor: c_uint,
    pub set_host: unsafe extern "C" fn(host: *mut OfxHost),
    pub main_entry: MainEntry,
}

// The plugin's description is static data that only the host reads.
unsafe impl Sync for OfxPlugin {}

/// `OfxPropertySuiteV1`.
#[repr(C)]
pub struct OfxPropertySuiteV1 {
    pub prop_set_pointer:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *mut c_void) -> OfxStatus,
    pub prop_set_string:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *const c_char) -> OfxStatus,
    pub prop_set_double: unsafe extern "C" fn(Handle, *const c_char, c_int, c_double) -> OfxStatus,
    pub prop_set_int: unsafe extern "C" fn(Handle, *const c_char, c_int, c_int) -> OfxStatus,
    pub prop_set_pointer_n:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *const *mut c_void) -> OfxStatus,
    pub prop_set_string_n:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *const *const c_char) -> OfxStatus,
    pub prop_set_double_n:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *const c_double) -> OfxStatus,
    pub prop_set_int_n:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *const c_int) -> OfxStatus,
    pub prop_get_pointer:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *mut *mut c_void) -> OfxStatus,
    pub prop_get_string:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *mut *mut c_char) -> OfxStatus,
    pub prop_get_double:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *mut c_double) -> OfxStatus,
    pub prop_get_int: unsafe extern "C" fn(Handle, *const c_char, c_int, *mut c_int) -> OfxStatus,
    pub prop_get_pointer_n:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *mut *mut c_void) -> OfxStatus,
    pub prop_get_string_n:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *mut *mut c_char) -> OfxStatus,
    pub prop_get_double_n:
        unsafe extern "C" fn(Handle, *const c_char, c_int, *mut c_double) -> OfxStatus,
    pub prop_get_int_n: unsafe extern "C" fn(Handle, *const c_char, c_int, *mut c_int) -> OfxStatus,
    pub prop_reset: unsafe extern "C" fn(Handle, *const c_char) -> OfxStatus,
    pub prop_get_dimension: unsafe extern "C" fn(Handle, *const c_char, *mut c_int) -> OfxStatus,
}

/// `OfxImageEffectSuiteV1`.
#[repr(C)]
pub struct OfxImageEffectSuiteV1 {
    pub get_property_set: unsafe extern "C" fn(Handle, *mut OfxPropertySetHandle) -> OfxStatus,
    pub get_param_set: unsafe extern "C" fn(Handle, *mut OfxParamSetHandle) -> OfxStatus,
    pub clip_define:
        unsafe extern "C" fn(Handle, *const c_char, *mut OfxPropertySetHandle) -> OfxStatus,
    pub clip_get_handle: unsafe extern "C" fn(
        Handle,
        *const c_char,
        *mut OfxImageClipHandle,
        *mut OfxPropertySetHandle,
    ) -> OfxStatus,
    pub clip_get_property_set:
        unsafe extern "C" fn(OfxImageClipHandle, *mut OfxPropertySetHandle) -> OfxStatus,
    pub clip_get_image: unsafe extern "C" fn(
        OfxImageClipHandle,
        OfxTime,
        *const OfxRectD,
        *mut OfxPropertySetHandle,
    ) -> OfxStatus,
    pub clip_release_image: unsafe extern "C" fn(OfxPropertySetHandle) -> OfxStatus,
    pub clip_get_region_of_definition:
        unsafe extern "C" fn(OfxImageClipHandle, OfxTime, *mut OfxRectD) -> OfxStatus,
    pub abort: unsafe extern "C" fn(Handle) -> c_int,
    pub image_memory_alloc:
        unsafe extern "C" fn(Handle, usize, *mut OfxImageMemoryHandle) -> OfxStatus,
    pub image_memory_free: unsafe extern "C" fn(OfxImageMemoryHandle) -> OfxStatus,
    pub image_memory_lock:
        unsafe extern "C" fn(OfxImageMemoryHandle, *mut *mut c_void) -> OfxStatus,
    pub image_memory_unlock: unsafe extern "C" fn(OfxImageMemoryHandle) -> OfxStatus,
}

/// `OfxParameterSuiteV1`. The value functions are C variadics: a value's
/// type follows from its parameter's.
#[repr(C)]
pub struct OfxParameterSuiteV1 {
    pub param_define: unsafe extern "C" fn(
        OfxParamSetHandle,
        *const c_char,
        *const c_char,
        *mut OfxPropertySetHandle,
    ) -> OfxStatus,
    pub param_get_handle: unsafe extern "C" fn(
        OfxParamSetHandle,
        *const c_char,
        *mut OfxParamHandle,
        *mut OfxPropertySetHandle,
    ) -> OfxStatus,
    pub param_set_get_property_set:
        unsafe extern "C" fn(OfxParamSetHandle, *mut OfxPropertySetHandle) -> OfxStatus,
    pub param_get_property_set:
        unsafe extern "C" fn(OfxParamHandle, *mut OfxPropertySetHandle) -> OfxStatus,
    pub param_get_value: unsafe extern "C" fn(OfxParamHandle, ...) -> OfxStatus,
    pub param_get_value_at_time: unsafe extern "C" fn(OfxParamHandle, OfxTime, ...) -> OfxStatus,
    pub param_get_derivative: unsafe extern "C" fn(OfxParamHandle, OfxTime, ...) -> OfxStatus,
    pub param_get_integral:
        unsafe extern "C" fn(OfxParamHandle, OfxTime, OfxTime, ...) -> OfxStatus,
    pub param_set_value: unsafe extern "C" fn(OfxParamHandle, ...) -> OfxStatus,
    pub param_set_value_at_time: unsafe extern "C" fn(OfxParamHandle, OfxTime, ...) -> OfxStatus,
    pub param_get_num_keys: unsafe extern "C" fn(OfxParamHandle, *mut c_uint) -> OfxStatus,
    pub param_get_key_time: unsafe extern "C" fn(OfxParamHandle, c_uint, *mut OfxTime) -> OfxStatus,
    pub param_get_key_index:
        unsafe extern "C" fn(OfxParamHandle, OfxTime, c_int, *mut c_int) -> OfxStatus,
    pub param_delete_key: unsafe extern "C" fn(OfxParamHandle, OfxTime) -> OfxStatus,
    pub param_delete_all_keys: unsafe extern "C" fn(OfxParamHandle) -> OfxStatus,
    pub param_copy: unsafe extern "C" fn(
        OfxParamHandle,
        OfxParamHandle,
        OfxTime,
        *const OfxRangeD,
    ) -> OfxStatus,
    pub param_edit_begin: unsafe extern "C" fn(OfxParamSetHandle, *const c_char) -> OfxStatus,
    pub param_edit_end: unsafe extern "C" fn(OfxParamSetHandle) -> OfxStatus,
}

/// `OfxMemorySuiteV1`.
#[repr(C)]
pub struct OfxMemorySuiteV1 {
    pub memory_alloc: unsafe extern "C" fn(Handle, usize, *mut *mut c_void) -> OfxStatus,
    pub memory_free: unsafe extern "C" fn(*mut c_void) -> OfxStatus,
}

/// `OfxThreadFunctionV1`.
pub type ThreadFunction = unsafe extern "C" fn(index: c_uint, count: c_uint, argument: *mut c_void);

/// `OfxMultiThreadSuiteV1`.
#[repr(C)]
pub struct OfxMultiThreadSuiteV1 {
    pub multi_thread: unsafe extern "C" fn(ThreadFunction, c_uint, *mut c_void) -> OfxStatus,
    pub multi_thread_num_cpus: unsafe extern "C" fn(*mut c_uint) -> OfxStatus,
    pub multi_thread_index: unsafe extern "C" fn(*mut c_uint) -> OfxStatus,
    pub multi_thread_is_spawned_thread: unsafe extern "C" fn() -> c_int,
    pub mutex_create: unsafe extern "C" fn(*mut OfxMutexHandle, c_int) -> OfxStatus,
    pub mutex_destroy: unsafe extern "C" fn(OfxMutexHandle) -> OfxStatus,
    pub mutex_lock: unsafe extern "C" fn(OfxMutexHandle) -> OfxStatus,
    pub mutex_unlock: unsafe extern "C" fn(OfxMutexHandle) -> OfxStatus,
    pub mutex_try_lock: unsafe extern "C" fn(OfxMutexHandle) -> OfxStatus,
}

/// `OfxMessageSuiteV1`: a printf format and its arguments.
#[repr(C)]
pub struct OfxMessageSuiteV1 {
    pub message:
        unsafe extern "C" fn(Handle, *const c_char, *const c_char, *const c_char, ...) -> OfxStatus,
}

/// The names the two sides agree on, as C strings.
pub mod names {
    use super::CStr;

    pub const IMAGE_EFFECT_PLUGIN_API: &CStr = c"OfxImageEffectPluginAPI";

    pub const PROPERTY_SUITE: &CStr = c"OfxPropertySuite";
    pub const IMAGE_EFFECT_SUITE: &CStr = c"OfxImageEffectSuite";
    pub const PARAMETER_SUITE: &CStr = c"OfxParameterSuite";
    pub const MEMORY_SUITE: &CStr = c"OfxMemorySuite";
    pub const MULTI_THREAD_SUITE: &CStr = c"OfxMultiThreadSuite";
    pub const MESSAGE_SUITE: &CStr = c"OfxMessageSuite";

    pub const ACTION_LOAD: &CStr = c"OfxActionLoad";
    pub const ACTION_UNLOAD: &CStr = c"OfxActionUnload";
    pub const ACTION_DESCRIBE: &CStr = c"OfxActionDescribe";
    pub const ACTION_CREATE_INSTANCE: &CStr = c"OfxActionCreateInstance";
    pub const ACTION_DESTROY_INSTANCE: &CStr = c"OfxActionDestroyInstance";
    pub const ACTION_PURGE_CACHES: &CStr = c"OfxActionPurgeCaches";
    pub const ACTION_DESCRIBE_IN_CONTEXT: &CStr = c"OfxImageEffectActionDescribeInContext";
    pub const ACTION_GET_REGION_OF_DEFINITION: &CStr = c"OfxImageEffectActionGetRegionOfDefinition";
    pub const ACTION_GET_REGIONS_OF_INTEREST: &CStr = c"OfxImageEffectActionGetRegionsOfInterest";
    pub const ACTION_GET_CLIP_PREFERENCES: &CStr = c"OfxImageEffectActionGetClipPreferences";
    pub const ACTION_IS_IDENTITY: &CStr = c"OfxImageEffectActionIsIdentity";
    pub const ACTION_BEGIN_SEQUENCE_RENDER: &CStr = c"OfxImageEffectActionBeginSequenceRender";
    pub const ACTION_RENDER: &CStr = c"OfxImageEffectActionRender";
    pub const ACTION_END_SEQUENCE_RENDER: &CStr = c"OfxImageEffectActionEndSequenceRender";

    pub const CONTEXT_FILTER: &CStr = c"OfxImageEffectContextFilter";
    pub const CONTEXT_GENERAL: &CStr = c"OfxImageEffectContextGeneral";

    pub const TYPE_IMAGE_EFFECT_HOST: &CStr = c"OfxTypeImageEffectHost";
    pub const TYPE_IMAGE_EFFECT: &CStr = c"OfxTypeImageEffect";
    pub const TYPE_IMAGE_EFFECT_INSTANCE: &CStr = c"OfxTypeImageEffectInstance";
    pub const TYPE_CLIP: &CStr = c"OfxTypeClip";
    pub const TYPE_IMAGE: &CStr = c"OfxTypeImage";
    pub const TYPE_PARAMETER: &CStr = c"OfxTypeParameter";

    pub const PROP_TYPE: &CStr = c"OfxPropType";
    pub const PROP_NAME: &CStr = c"OfxPropName";
    pub const PROP_LABEL: &CStr = c"OfxPropLabel";
    pub const PROP_TIME: &CStr = c"OfxPropTime";
    pub const PROP_INSTANCE_DATA: &CStr = c"OfxPropInstanceData";
    pub const PROP_IS_INTERACTIVE: &CStr = c"OfxPropIsInteractive";
    pub const PROP_PLUGIN_DESCRIPTION: &CStr = c"OfxPropPluginDescription";
    pub const PROP_VERSION: &CStr = c"OfxPropVersion";

    pub const EFFECT_CONTEXT: &CStr = c"OfxImageEffectPropContext";
    pub const EFFECT_GROUPING: &CStr = c"OfxImageEffectPluginPropGrouping";
    pub const EFFECT_SUPPORTED_CONTEXTS: &CStr = c"OfxImageEffectPropSupportedContexts";
    pub const EFFECT_SUPPORTED_PIXEL_DEPTHS: &CStr = c"OfxImageEffectPropSupportedPixelDepths";
    pub const EFFECT_SUPPORTED_COMPONENTS: &CStr = c"OfxImageEffectPropSupportedComponents";
    pub const EFFECT_SUPPORTS_TILES: &CStr = c"OfxImageEffectPropSupportsTiles";
    pub const EFFECT_SUPPORTS_MULTI_RESOLUTION: &CStr =
        c"OfxImageEffectPropSupportsMultiResolution";
    pub const EFFECT_RENDER_THREAD_SAFETY: &CStr = c"OfxImageEffectPluginRenderThreadSafety";
    pub const EFFECT_HOST_FRAME_THREADING: &CStr = c"OfxImageEffectPluginPropHostFrameThreading";
    pub const RENDER_FULLY_SAFE: &CStr = c"OfxImageEffectRenderFullySafe";
    pub const EFFECT_PROJECT_SIZE: &CStr = c"OfxImageEffectPropProjectSize";
    pub const EFFECT_PROJECT_OFFSET: &CStr = c"OfxImageEffectPropProjectOffset";
    pub const EFFECT_PROJECT_EXTENT: &CStr = c"OfxImageEffectPropProjectExtent";
    pub const EFFECT_PROJECT_PIXEL_ASPECT_RATIO: &CStr =
        c"OfxImageEffectPropProjectPixelAspectRatio";
    pub const EFFECT_RENDER_SCALE: &CStr = c"OfxImageEffectPropRenderScale";
    pub const EFFECT_RENDER_WINDOW: &CStr = c"OfxImageEffectPropRenderWindow";
    pub const EFFECT_FRAME_RANGE: &CStr = c"OfxImageEffectPropFrameRange";
    pub const EFFECT_FRAME_STEP: &CStr = c"OfxImageEffectPropFrameStep";
    pub const EFFECT_FIELD_TO_RENDER: &CStr = c"OfxImageEffectPropFieldToRender";
    pub const EFFECT_REGION_OF_DEFINITION: &CStr = c"OfxImageEffectPropRegionOfDefinition";
    pub const EFFECT_PIXEL_DEPTH: &CStr = c"OfxImageEffectPropPixelDepth";
    pub const EFFECT_COMPONENTS: &CStr = c"OfxImageEffectPropComponents";
    pub const EFFECT_PREMULTIPLICATION: &CStr = c"OfxImageEffectPropPreMultiplication";
    /// The region of interest on the source clip: `kOfxImageClipPropRoI_`
    /// followed by the clip's name.
    pub const SOURCE_REGION_OF_INTEREST: &CStr = c"OfxImageClipPropRoI_Source";

    pub const CLIP_SOURCE: &CStr = c"Source";
    pub const CLIP_OUTPUT: &CStr = c"Output";
    pub const CLIP_CONNECTED: &CStr = c"OfxImageClipPropConnected";

    pub const IMAGE_DATA: &CStr = c"OfxImagePropData";
    pub const IMAGE_BOUNDS: &CStr = c"OfxImagePropBounds";
    pub const IMAGE_ROW_BYTES: &CStr = c"OfxImagePropRowBytes";
    pub const IMAGE_PIXEL_ASPECT_RATIO: &CStr = c"OfxImagePropPixelAspectRatio";
    pub const IMAGE_REGION_OF_DEFINITION: &CStr = c"OfxImagePropRegionOfDefinition";
    pub const IMAGE_FIELD: &CStr = c"OfxImagePropField";

    pub const BIT_DEPTH_FLOAT: &CStr = c"OfxBitDepthFloat";
    pub const COMPONENT_RGBA: &CStr = c"OfxImageComponentRGBA";
    pub const COMPONENT_RGB: &CStr = c"OfxImageComponentRGB";

    pub const PARAM_TYPE_DOUBLE: &CStr = c"OfxParamTypeDouble";
    pub const PARAM_TYPE_INTEGER: &CStr = c"OfxParamTypeInteger";
    pub const PARAM_TYPE_BOOLEAN: &CStr = c"OfxParamTypeBoolean";
    pub const PARAM_TYPE_CHOICE: &CStr = c"OfxParamTypeChoice";
    pub const PARAM_TYPE_STRING: &CStr = c"OfxParamTypeString";
    pub const PARAM_TYPE_GROUP: &CStr = c"OfxParamTypeGroup";

    pub const PARAM_DEFAULT: &CStr = c"OfxParamPropDefault";
    pub const PARAM_MIN: &CStr = c"OfxParamPropMin";
    pub const PARAM_MAX: &CStr = c"OfxParamPropMax";
    pub const PARAM_DISPLAY_MIN: &CStr = c"OfxParamPropDisplayMin";
    pub const PARAM_DISPLAY_MAX: &CStr = c"OfxParamPropDisplayMax";
    pub const PARAM_HINT: &CStr = c"OfxParamPropHint";
    pub const PARAM_PARENT: &CStr = c"OfxParamPropParent";
    pub const PARAM_CHOICE_OPTION: &CStr = c"OfxParamPropChoiceOption";
    pub const PARAM_STRING_MODE: &CStr = c"OfxParamPropStringMode";
    pub const PARAM_STRING_IS_FILE_PATH: &CStr = c"OfxParamStringIsFilePath";
    pub const PARAM_FILE_PATH_EXISTS: &CStr = c"OfxParamPropStringFilePathExists";
    pub const PARAM_ANIMATES: &CStr = c"OfxParamPropAnimates";

    pub const MESSAGE_ERROR: &CStr = c"OfxMessageError";
    pub const MESSAGE_WARNING: &CStr = c"OfxMessageWarning";
}
