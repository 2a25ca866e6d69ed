//! The frozen wire layout of every message.
//!
//! Each struct's size, alignment, field offsets and field types are asserted at compile time
//! (a layout change does not build until this table, the type names' version and the C header
//! are updated), and every field is contiguous with the next: no implicit padding, so the bytes
//! on the wire are fully defined. The same table is public so that tests (and bindings for
//! other languages) can compare against it: `tests/c_header.rs` checks
//! `include/cablevib_ipc.h` against [`ALL_LAYOUTS`] with a C compiler.

use crate::messages::{
    EstimateSample, MarginRequest, MarginResponse, Message, PoseSample, TminSetpoint,
    VibrationSample,
};

/// Layout of one field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FieldLayout {
    /// Field name (the same in Rust and C).
    pub name: &'static str,
    /// Offset from the start of the struct, bytes.
    pub offset: usize,
    /// Size, bytes.
    pub size: usize,
    /// Scalar element type: `"u32"`, `"u64"` or `"f64"` (`uint32_t`, `uint64_t`, `double`).
    pub elem: &'static str,
    /// Number of elements: 1 for a scalar, N for an array `[T; N]`.
    pub len: usize,
}

/// Layout of one message struct.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StructLayout {
    /// Rust type name.
    pub rust_name: &'static str,
    /// C struct (typedef) name in `include/cablevib_ipc.h`.
    pub c_name: &'static str,
    /// iceoryx2 type name.
    pub type_name: &'static str,
    /// `size_of`, bytes.
    pub size: usize,
    /// `align_of`, bytes.
    pub align: usize,
    /// Every field, in declaration (= offset) order.
    pub fields: &'static [FieldLayout],
}

/// A field type allowed on the wire.
trait WireType {
    const ELEM: &'static str;
    const LEN: usize;
}
impl WireType for u32 {
    const ELEM: &'static str = "u32";
    const LEN: usize = 1;
}
impl WireType for u64 {
    const ELEM: &'static str = "u64";
    const LEN: usize = 1;
}
impl WireType for f64 {
    const ELEM: &'static str = "f64";
    const LEN: usize = 1;
}
impl<T: WireType, const N: usize> WireType for [T; N] {
    const ELEM: &'static str = T::ELEM;
    const LEN: usize = N;
}

/// Asserts at compile time the layout of `$ty` (size, alignment, each field's type and offset,
/// no padding anywhere) and defines the public table entry `$table`.
macro_rules! frozen_layout {
    (
        $(#[$doc:meta])*
        $table:ident = $ty:ident { size: $size:literal, align: $align:literal, fields: {
            $($field:ident: $fty:ty = $off:literal),+ $(,)?
        } }
    ) => {
        const _: () = {
            use core::mem::{align_of, offset_of, size_of};
            const Z: $ty = <$ty>::zeroed();
            assert!(size_of::<$ty>() == $size, concat!("size of ", stringify!($ty), " changed"));
            assert!(
                align_of::<$ty>() == $align,
                concat!("alignment of ", stringify!($ty), " changed")
            );
            $(
                // The field has exactly the declared type ...
                let _: $fty = Z.$field;
                // ... at the declared offset.
                assert!(
                    offset_of!($ty, $field) == $off,
                    concat!("offset of ", stringify!($ty), "::", stringify!($field), " changed")
                );
            )+
            // Fields are contiguous and fill the struct: no implicit padding.
            let offsets = [$($off),+];
            let sizes = [$(size_of::<$fty>()),+];
            let mut end = 0;
            let mut i = 0;
            while i < offsets.len() {
                assert!(
                    offsets[i] == end,
                    concat!("implicit padding inside ", stringify!($ty))
                );
                end += sizes[i];
                i += 1;
            }
            assert!(end == $size, concat!("trailing padding in ", stringify!($ty)));
        };

        $(#[$doc])*
        pub const $table: StructLayout = StructLayout {
            rust_name: stringify!($ty),
            c_name: <$ty as Message>::C_NAME,
            type_name: <$ty as Message>::TYPE_NAME,
            size: $size,
            align: $align,
            fields: &[$(FieldLayout {
                name: stringify!($field),
                offset: $off,
                size: core::mem::size_of::<$fty>(),
                elem: <$fty as WireType>::ELEM,
                len: <$fty as WireType>::LEN,
            }),+],
        };
    };
}

frozen_layout! {
    /// Layout of [`PoseSample`]: 80 bytes.
    POSE_SAMPLE_LAYOUT = PoseSample { size: 80, align: 8, fields: {
        sequence: u64 = 0,
        timestamp_ns: u64 = 8,
        position_m: [f64; 3] = 16,
        orientation_wxyz: [f64; 4] = 40,
        flags: u32 = 72,
        reserved0: u32 = 76,
    } }
}

frozen_layout! {
    /// Layout of [`TminSetpoint`]: 160 bytes.
    T_MIN_SETPOINT_LAYOUT = TminSetpoint { size: 160, align: 8, fields: {
        sequence: u64 = 0,
        timestamp_ns: u64 = 8,
        t_min_n: f64 = 16,
        per_cable_count: u32 = 24,
        reserved0: u32 = 28,
        per_cable_t_min_n: [f64; 16] = 32,
    } }
}

frozen_layout! {
    /// Layout of [`EstimateSample`]: 592 bytes.
    ESTIMATE_SAMPLE_LAYOUT = EstimateSample { size: 592, align: 8, fields: {
        pose_sequence: u64 = 0,
        pose_timestamp_ns: u64 = 8,
        receive_timestamp_ns: u64 = 16,
        publish_timestamp_ns: u64 = 24,
        status: u32 = 32,
        cable_count: u32 = 36,
        tensions_n: [f64; 16] = 40,
        f1_hz: f64 = 168,
        ee_mode_hz: f64 = 176,
        stiffness_dim: u32 = 184,
        ee_mode_age_cycles: u32 = 188,
        stiffness: [f64; 36] = 192,
        compute_ns: u64 = 480,
        eigen_evaluations: u32 = 488,
        tension_iterations: u32 = 492,
        eigen_residual: f64 = 496,
        skipped_poses: u64 = 504,
        sequence: u64 = 512,
        measured_f1_hz: f64 = 520,
        f1_residual_hz: f64 = 528,
        measured_ee_mode_hz: f64 = 536,
        ee_mode_residual_hz: f64 = 544,
        measured_age_ns: u64 = 552,
        measured_f1_status: u32 = 560,
        measured_ee_mode_status: u32 = 564,
        vibration_samples: u64 = 568,
        vibration_refused: u64 = 576,
        vibration_lost: u64 = 584,
    } }
}

frozen_layout! {
    /// Layout of [`MarginRequest`]: 24 bytes.
    MARGIN_REQUEST_LAYOUT = MarginRequest { size: 24, align: 8, fields: {
        sequence: u64 = 0,
        timestamp_ns: u64 = 8,
        required_f1_hz: f64 = 16,
    } }
}

frozen_layout! {
    /// Layout of [`MarginResponse`]: 64 bytes.
    MARGIN_RESPONSE_LAYOUT = MarginResponse { size: 64, align: 8, fields: {
        request_sequence: u64 = 0,
        pose_sequence: u64 = 8,
        status: u32 = 16,
        t_min_required_age_cycles: u32 = 20,
        f1_hz: f64 = 24,
        margin_hz: f64 = 32,
        margin_ratio: f64 = 40,
        t_min_required_n: f64 = 48,
        timestamp_ns: u64 = 56,
    } }
}

frozen_layout! {
    /// Layout of [`VibrationSample`]: 72 bytes.
    VIBRATION_SAMPLE_LAYOUT = VibrationSample { size: 72, align: 8, fields: {
        sequence: u64 = 0,
        timestamp_ns: u64 = 8,
        acceleration_m_s2: [f64; 3] = 16,
        angular_velocity_rad_s: [f64; 3] = 40,
        flags: u32 = 64,
        reserved0: u32 = 68,
    } }
}

/// The layout of every message type, in the order pose, T_min, estimate, margin request,
/// margin response, vibration.
pub const ALL_LAYOUTS: [StructLayout; 6] = [
    POSE_SAMPLE_LAYOUT,
    T_MIN_SETPOINT_LAYOUT,
    ESTIMATE_SAMPLE_LAYOUT,
    MARGIN_REQUEST_LAYOUT,
    MARGIN_RESPONSE_LAYOUT,
    VIBRATION_SAMPLE_LAYOUT,
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_consistent() {
        for l in ALL_LAYOUTS {
            let end = l.fields.iter().fold(0, |end, f| {
                assert_eq!(f.offset, end, "{}::{}", l.rust_name, f.name);
                assert_eq!(f.size, f.len * if f.elem == "u32" { 4 } else { 8 });
                end + f.size
            });
            assert_eq!(end, l.size, "{}", l.rust_name);
            assert_eq!(l.size % l.align, 0);
        }
    }
}
