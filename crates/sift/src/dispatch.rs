//! Run-time CPU dispatch: one function compiled once per target feature, the best the CPU has picked
//! at each call (the model is memchr's `unsafe_ifunc!`, without its cached function pointer: the
//! detection macro caches the CPU's features itself, and the call sites are per row or per keypoint).

/// Defines a function that runs the best of its feature-specific copies the CPU supports.
///
/// ```text
/// cpu_dispatch! {
///     /// Docs of the function.
///     pub fn name(a: &[f32], n: usize) -> f32;
///     "avx512f" => name_avx512 => name_impl::<true>(a, n);
///     "avx2" => name_avx2 => name_impl::<false>(a, n);
///     _ => name_impl::<false>(a, n)
/// }
/// ```
///
/// Each `"feature" => copy => expression` arm compiles `expression` inside a function `copy` that has the
/// target feature enabled, so the `#[inline(always)]` body it calls is generated for that feature; arms are
/// tried in order, and the last line is the portable fallback. On targets other than x86-64 only the fallback
/// exists. Used by this crate's Gaussian blur, extrema scan, edge mask, orientation and descriptor, and by
/// `mrslam-merge`'s descriptor matching.
#[macro_export]
macro_rules! cpu_dispatch {
    (
        $(#[$attr:meta])*
        $vis:vis fn $name:ident($($arg:ident: $ty:ty),* $(,)?) $(-> $ret:ty)?;
        $($arms:tt)*
    ) => {
        $(#[$attr])*
        $vis fn $name($($arg: $ty),*) $(-> $ret)? {
            $crate::cpu_dispatch!(@arms [$($arg: $ty),*] [$($arg),*] [$(-> $ret)?] $($arms)*)
        }
    };
    // The portable fallback.
    (@arms [$($sig:tt)*] [$($names:tt)*] [$($ret:tt)*] _ => $fallback:expr $(;)?) => {
        $fallback
    };
    // One feature's copy, tried before the arms after it (a `tt`, not a `literal`: the detection macro
    // matches the feature's name token by token).
    (@arms [$($sig:tt)*] [$($names:tt)*] [$($ret:tt)*] $feature:tt => $copy:ident => $call:expr; $($rest:tt)*) => {{
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feature)]
        #[allow(clippy::too_many_arguments)]
        fn $copy($($sig)*) $($ret)* {
            $call
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!($feature) {
            // SAFETY: the CPU supports the copy's target feature (checked just above).
            return unsafe { $copy($($names)*) };
        }
        $crate::cpu_dispatch!(@arms [$($sig)*] [$($names)*] [$($ret)*] $($rest)*)
    }};
}
