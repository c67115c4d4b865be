/*
 * xmath.c - sin, cos, tan, atan, atan2, asin, acos, exp, log and pow from
 * plain double arithmetic (xmath.h; docs/maths.md has the error bounds).
 *
 * Methods (the textbook ones, written anew; constants and coefficients come
 * from common/xmath_gen.py):
 * - sin, cos, tan: argument reduction to r = x - n pi/2, |r| <= pi/4, kept as
 *   a double-double: Cody-Waite with pi/2 in three parts while |x| < 2^19
 *   pi/2, Payne-Hanek (integer multiply by 2/pi's bits) beyond; then
 *   polynomials interpolated at Chebyshev nodes (near minimax).
 * - atan: reduction atan(x) = atan(c) + atan((x - c)/(1 + x c)), c = i/8
 *   (a table of atan(c) as double-doubles), atan(x) = pi/2 - atan(1/x) above
 *   4; the quotient and the sums are kept as double-doubles. atan2, asin and
 *   acos are quotients for the same kernel (asin x = atan(x / sqrt(1 - x^2))
 *   with 1 - x^2 and its root in double-double).
 * - exp: x = (64 k + j) ln2/64 + r, exp(x) = 2^k 2^(j/64) exp(r), |r| <=
 *   ln2/128 (Tang's table method).
 * - log: x = 2^k m, m near F = j/128, log x = k ln2 + log F + log1p((m - F)/F),
 *   all as a double-double; pow(x, y) = exp(y log x) with both in
 *   double-double, so its error stays below one ulp for every result.
 *
 * Double-double building blocks: two_sum (Knuth), fast_two_sum (Dekker) and
 * two_prod by Veltkamp splitting (Dekker), exact without an fma. Nothing here
 * may be contracted or reassociated: the Makefile builds with
 * -ffp-contract=off and xmath.h refuses the flags that would.
 */
#include "common/xmath.h"

#include <math.h> /* fabs, floor, sqrt: exact or correctly rounded */
#include <stdint.h>
#include <string.h>

#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

/* ---- constants, tables and coefficients (output of common/xmath_gen.py) ---- */

/* sin_c: 7 coefficients, max relative error of the fit 2^-57.1 */
static const double sin_c[7] = { -0x1.5555555555555p-3, 0x1.1111111111110p-7, -0x1.a01a01a019938p-13, 0x1.71de3a546095bp-19, -0x1.ae645412c560cp-26, 0x1.61217f0b800d5p-33, -0x1.ab17d404de5b3p-41 };
/* cos_c: 7 coefficients, max relative error of the fit 2^-59.5 */
static const double cos_c[7] = { 0x1.5555555555555p-5, -0x1.6c16c16c16c16p-10, 0x1.a01a01a019d0ap-16, -0x1.27e4fb7712d65p-22, 0x1.1eed8deb97a97p-29, -0x1.9394ba0cd6ed5p-37, 0x1.ab785b00b4646p-45 };
/* atan_c: 6 coefficients, max relative error of the fit 2^-64.0 */
static const double atan_c[6] = { -0x1.5555555555555p-2, 0x1.9999999999986p-3, -0x1.249249247f30ep-3, 0x1.c71c70f2345bap-4, -0x1.745afe91c1d6ap-4, 0x1.38a3954748032p-4 };
/* atan_s: 3 coefficients, max relative error of the fit 2^-64.2 */
static const double atan_s[3] = { -0x1.5555555555547p-2, 0x1.9999999199bf7p-3, -0x1.248cf3e2df98ep-3 };
/* asin_c: 13 coefficients, max relative error of the fit 2^-57.4 */
static const double asin_c[13] = { 0x1.5555555555556p-3, 0x1.3333333332ecap-4, 0x1.6db6db6e31f13p-5, 0x1.f1c71c1db0623p-6, 0x1.6e8bb1c8209a2p-6, 0x1.1c4d35cf95421p-6, 0x1.c9cf07674736ap-7, 0x1.782651caa6547p-7, 0x1.52420b04b37bep-7, 0x1.65a9c4dfcf8b2p-8, 0x1.1d189408314eep-6, -0x1.e6aaa8a0a04ccp-7, 0x1.d72b2bc8155f8p-6 };
/* exp_c: 4 coefficients, max relative error of the fit 2^-60.4 */
static const double exp_c[4] = { 0x1.5555555555236p-3, 0x1.55555555553c6p-5, 0x1.11111dd009952p-7, 0x1.6c16ce2b0f35fp-10 };
/* log1p_c: 6 coefficients, max relative error of the fit 2^-67.8 */
static const double log1p_c[6] = { 0x1.5555555555557p-2, -0x1.0000000000002p-2, 0x1.99999997789e7p-3, -0x1.555555536ad9ap-3, 0x1.249509760c9fbp-3, -0x1.000279e304663p-3 };
/* 2^(j/64), j = 0..63, as hi + lo */
static const double exp_tab[64][2] = {
	{ 0x1.0000000000000p+0, 0x0.0p+0 },
	{ 0x1.02c9a3e778061p+0, -0x1.19083535b085dp-56 },
	{ 0x1.059b0d3158574p+0, 0x1.d73e2a475b465p-55 },
	{ 0x1.0874518759bc8p+0, 0x1.186be4bb284ffp-57 },
	{ 0x1.0b5586cf9890fp+0, 0x1.8a62e4adc610bp-54 },
	{ 0x1.0e3ec32d3d1a2p+0, 0x1.03a1727c57b53p-59 },
	{ 0x1.11301d0125b51p+0, -0x1.6c51039449b3ap-54 },
	{ 0x1.1429aaea92de0p+0, -0x1.32fbf9af1369ep-54 },
	{ 0x1.172b83c7d517bp+0, -0x1.19041b9d78a76p-55 },
	{ 0x1.1a35beb6fcb75p+0, 0x1.e5b4c7b4968e4p-55 },
	{ 0x1.1d4873168b9aap+0, 0x1.e016e00a2643cp-54 },
	{ 0x1.2063b88628cd6p+0, 0x1.dc775814a8495p-55 },
	{ 0x1.2387a6e756238p+0, 0x1.9b07eb6c70573p-54 },
	{ 0x1.26b4565e27cddp+0, 0x1.2bd339940e9d9p-55 },
	{ 0x1.29e9df51fdee1p+0, 0x1.612e8afad1255p-55 },
	{ 0x1.2d285a6e4030bp+0, 0x1.0024754db41d5p-54 },
	{ 0x1.306fe0a31b715p+0, 0x1.6f46ad23182e4p-55 },
	{ 0x1.33c08b26416ffp+0, 0x1.32721843659a6p-54 },
	{ 0x1.371a7373aa9cbp+0, -0x1.63aeabf42eae2p-54 },
	{ 0x1.3a7db34e59ff7p+0, -0x1.5e436d661f5e3p-56 },
	{ 0x1.3dea64c123422p+0, 0x1.ada0911f09ebcp-55 },
	{ 0x1.4160a21f72e2ap+0, -0x1.ef3691c309278p-58 },
	{ 0x1.44e086061892dp+0, 0x1.89b7a04ef80d0p-59 },
	{ 0x1.486a2b5c13cd0p+0, 0x1.3c1a3b69062f0p-56 },
	{ 0x1.4bfdad5362a27p+0, 0x1.d4397afec42e2p-56 },
	{ 0x1.4f9b2769d2ca7p+0, -0x1.4b309d25957e3p-54 },
	{ 0x1.5342b569d4f82p+0, -0x1.07abe1db13cadp-55 },
	{ 0x1.56f4736b527dap+0, 0x1.9bb2c011d93adp-54 },
	{ 0x1.5ab07dd485429p+0, 0x1.6324c054647adp-54 },
	{ 0x1.5e76f15ad2148p+0, 0x1.ba6f93080e65ep-54 },
	{ 0x1.6247eb03a5585p+0, -0x1.383c17e40b497p-54 },
	{ 0x1.6623882552225p+0, -0x1.bb60987591c34p-54 },
	{ 0x1.6a09e667f3bcdp+0, -0x1.bdd3413b26456p-54 },
	{ 0x1.6dfb23c651a2fp+0, -0x1.bbe3a683c88abp-57 },
	{ 0x1.71f75e8ec5f74p+0, -0x1.16e4786887a99p-55 },
	{ 0x1.75feb564267c9p+0, -0x1.0245957316dd3p-54 },
	{ 0x1.7a11473eb0187p+0, -0x1.41577ee04992fp-55 },
	{ 0x1.7e2f336cf4e62p+0, 0x1.05d02ba15797ep-56 },
	{ 0x1.82589994cce13p+0, -0x1.d4c1dd41532d8p-54 },
	{ 0x1.868d99b4492edp+0, -0x1.fc6f89bd4f6bap-54 },
	{ 0x1.8ace5422aa0dbp+0, 0x1.6e9f156864b27p-54 },
	{ 0x1.8f1ae99157736p+0, 0x1.5cc13a2e3976cp-55 },
	{ 0x1.93737b0cdc5e5p+0, -0x1.75fc781b57ebcp-57 },
	{ 0x1.97d829fde4e50p+0, -0x1.d185b7c1b85d1p-54 },
	{ 0x1.9c49182a3f090p+0, 0x1.c7c46b071f2bep-56 },
	{ 0x1.a0c667b5de565p+0, -0x1.359495d1cd533p-54 },
	{ 0x1.a5503b23e255dp+0, -0x1.d2f6edb8d41e1p-54 },
	{ 0x1.a9e6b5579fdbfp+0, 0x1.0fac90ef7fd31p-54 },
	{ 0x1.ae89f995ad3adp+0, 0x1.7a1cd345dcc81p-54 },
	{ 0x1.b33a2b84f15fbp+0, -0x1.2805e3084d708p-57 },
	{ 0x1.b7f76f2fb5e47p+0, -0x1.5584f7e54ac3bp-56 },
	{ 0x1.bcc1e904bc1d2p+0, 0x1.23dd07a2d9e84p-55 },
	{ 0x1.c199bdd85529cp+0, 0x1.11065895048ddp-55 },
	{ 0x1.c67f12e57d14bp+0, 0x1.2884dff483cadp-54 },
	{ 0x1.cb720dcef9069p+0, 0x1.503cbd1e949dbp-56 },
	{ 0x1.d072d4a07897cp+0, -0x1.cbc3743797a9cp-54 },
	{ 0x1.d5818dcfba487p+0, 0x1.2ed02d75b3707p-55 },
	{ 0x1.da9e603db3285p+0, 0x1.c2300696db532p-54 },
	{ 0x1.dfc97337b9b5fp+0, -0x1.1a5cd4f184b5cp-54 },
	{ 0x1.e502ee78b3ff6p+0, 0x1.39e8980a9cc8fp-55 },
	{ 0x1.ea4afa2a490dap+0, -0x1.e9c23179c2893p-54 },
	{ 0x1.efa1bee615a27p+0, 0x1.dc7f486a4b6b0p-54 },
	{ 0x1.f50765b6e4540p+0, 0x1.9d3e12dd8a18bp-54 },
	{ 0x1.fa7c1819e90d8p+0, 0x1.74853f3a5931ep-55 },
};
/* log(j/128), j = 90..181, as hi + lo */
static const double log_tab[92][2] = {
	{ -0x1.68ac83e9c6a14p-2, -0x1.a64eadd740178p-58 },
	{ -0x1.5d5bddf595f30p-2, 0x1.6541148cbb8a2p-56 },
	{ -0x1.522ae0738a3d8p-2, 0x1.8f7e9b38a6979p-57 },
	{ -0x1.4718dc271c41bp-2, -0x1.8fb4c14c56eefp-60 },
	{ -0x1.3c25277333184p-2, 0x1.2ad27e50a8ec6p-56 },
	{ -0x1.314f1e1d35ce4p-2, 0x1.3d69909e5c3dcp-56 },
	{ -0x1.269621134db92p-2, -0x1.e0efadd9db02bp-56 },
	{ -0x1.1bf99635a6b95p-2, 0x1.12aeb84249223p-57 },
	{ -0x1.1178e8227e47cp-2, 0x1.0e63a5f01c691p-57 },
	{ -0x1.07138604d5862p-2, -0x1.cdb16ed4e9138p-56 },
	{ -0x1.f991c6cb3b379p-3, -0x1.f665066f980a2p-57 },
	{ -0x1.e530effe71012p-3, -0x1.2276041f43042p-59 },
	{ -0x1.d1037f2655e7bp-3, -0x1.60629242471a2p-57 },
	{ -0x1.bd087383bd8adp-3, -0x1.dd355f6a516d7p-60 },
	{ -0x1.a93ed3c8ad9e3p-3, -0x1.bcafa9de97203p-57 },
	{ -0x1.95a5adcf7017fp-3, -0x1.142c507fb7a3dp-58 },
	{ -0x1.823c16551a3c2p-3, 0x1.1232ce70be781p-57 },
	{ -0x1.6f0128b756abcp-3, 0x1.8de59c21e166cp-57 },
	{ -0x1.5bf406b543db2p-3, 0x1.1f5b44c0df7e7p-61 },
	{ -0x1.4913d8333b561p-3, 0x1.0d5604930f135p-58 },
	{ -0x1.365fcb0159016p-3, -0x1.7d411a5b944adp-58 },
	{ -0x1.23d712a49c202p-3, 0x1.6e38161051d69p-57 },
	{ -0x1.1178e8227e47cp-3, 0x1.0e63a5f01c691p-58 },
	{ -0x1.fe89139dbd566p-4, 0x1.ac9f4215f9393p-58 },
	{ -0x1.da727638446a2p-4, -0x1.401fa71733019p-58 },
	{ -0x1.b6ac88dad5b1cp-4, 0x1.0057eed1ca59fp-59 },
	{ -0x1.9335e5d594989p-4, 0x1.478a85704ccb7p-58 },
	{ -0x1.700d30aeac0e1p-4, 0x1.72566212cdd05p-61 },
	{ -0x1.4d3115d207eacp-4, -0x1.769f42c7842ccp-58 },
	{ -0x1.2aa04a44717a5p-4, 0x1.d15d38d2fa3f7p-58 },
	{ -0x1.08598b59e3a07p-4, 0x1.dd7009902bf32p-58 },
	{ -0x1.ccb73cdddb2ccp-5, 0x1.e48fb0500efd4p-59 },
	{ -0x1.894aa149fb343p-5, -0x1.a8be97660a23dp-60 },
	{ -0x1.466aed42de3eap-5, 0x1.cdd6f7f4a137ep-59 },
	{ -0x1.0415d89e74444p-5, -0x1.c05cf1d753622p-59 },
	{ -0x1.8492528c8cabfp-6, 0x1.d192d0619fa67p-60 },
	{ -0x1.0205658935847p-6, -0x1.27c8e8416e71fp-60 },
	{ -0x1.010157588de71p-7, -0x1.46662d417ced0p-62 },
	{ 0x0.0p+0, 0x0.0p+0 },
	{ 0x1.fe02a6b106789p-8, -0x1.e44b7e3711ebfp-67 },
	{ 0x1.fc0a8b0fc03e4p-7, -0x1.83092c59642a1p-62 },
	{ 0x1.7b91b07d5b11bp-6, -0x1.5b602ace3a510p-60 },
	{ 0x1.f829b0e783300p-6, 0x1.33e3f04f1ef23p-60 },
	{ 0x1.39e87b9febd60p-5, -0x1.5bfa937f551bbp-59 },
	{ 0x1.77458f632dcfcp-5, 0x1.18d3ca87b9296p-59 },
	{ 0x1.b42dd711971bfp-5, -0x1.eb9759c130499p-60 },
	{ 0x1.f0a30c01162a6p-5, 0x1.85f325c5bbacdp-59 },
	{ 0x1.16536eea37ae1p-4, -0x1.79da3e8c22cdap-60 },
	{ 0x1.341d7961bd1d1p-4, -0x1.b599f227becbbp-58 },
	{ 0x1.51b073f06183fp-4, 0x1.a49e39a1a8be4p-58 },
	{ 0x1.6f0d28ae56b4cp-4, -0x1.906d99184b992p-58 },
	{ 0x1.8c345d6319b21p-4, -0x1.4a697ab3424a9p-61 },
	{ 0x1.a926d3a4ad563p-4, 0x1.942f48aa70ea9p-58 },
	{ 0x1.c5e548f5bc743p-4, 0x1.5d617ef8161b1p-60 },
	{ 0x1.e27076e2af2e6p-4, -0x1.61578001e0162p-60 },
	{ 0x1.fec9131dbeabbp-4, -0x1.5746b9981b36cp-58 },
	{ 0x1.0d77e7cd08e59p-3, 0x1.9a5dc5e9030acp-57 },
	{ 0x1.1b72ad52f67a0p-3, 0x1.483023472cd74p-58 },
	{ 0x1.29552f81ff523p-3, 0x1.301771c407dbfp-57 },
	{ 0x1.371fc201e8f74p-3, 0x1.de6cb62af18a0p-58 },
	{ 0x1.44d2b6ccb7d1ep-3, 0x1.9f4f6543e1f88p-57 },
	{ 0x1.526e5e3a1b438p-3, -0x1.746ff8a470d3ap-57 },
	{ 0x1.5ff3070a793d4p-3, -0x1.bc60efafc6f6ep-58 },
	{ 0x1.6d60fe719d21dp-3, -0x1.caae268ecd179p-57 },
	{ 0x1.7ab890210d909p-3, 0x1.be36b2d6a0608p-59 },
	{ 0x1.87fa06520c911p-3, -0x1.bf7fdbfa08d9ap-57 },
	{ 0x1.9525a9cf456b4p-3, 0x1.d904c1d4e2e26p-57 },
	{ 0x1.a23bc1fe2b563p-3, 0x1.93711b07a998cp-59 },
	{ 0x1.af3c94e80bff3p-3, -0x1.398cff3641985p-58 },
	{ 0x1.bc286742d8cd6p-3, 0x1.4fce744870f55p-58 },
	{ 0x1.c8ff7c79a9a22p-3, -0x1.4f689f8434012p-57 },
	{ 0x1.d5c216b4fbb91p-3, 0x1.6e443597e4d40p-57 },
	{ 0x1.e27076e2af2e6p-3, -0x1.61578001e0162p-59 },
	{ 0x1.ef0adcbdc5936p-3, 0x1.48637950dc20dp-57 },
	{ 0x1.fb9186d5e3e2bp-3, -0x1.caaae64f21acbp-57 },
	{ 0x1.0402594b4d041p-2, -0x1.28ec217a5022dp-57 },
	{ 0x1.0a324e27390e3p-2, 0x1.7dcfde8061c03p-56 },
	{ 0x1.1058bf9ae4ad5p-2, 0x1.89fa0ab4cb31dp-58 },
	{ 0x1.1675cababa60ep-2, 0x1.ce63eab883717p-61 },
	{ 0x1.1c898c16999fbp-2, -0x1.0e5c62aff1c44p-60 },
	{ 0x1.22941fbcf7966p-2, -0x1.76f5eb09628afp-56 },
	{ 0x1.2895a13de86a3p-2, 0x1.7ad24c13f040ep-56 },
	{ 0x1.2e8e2bae11d31p-2, -0x1.8f4cdb95ebdf9p-56 },
	{ 0x1.347dd9a987d55p-2, -0x1.4dd4c580919f8p-57 },
	{ 0x1.3a64c556945eap-2, -0x1.c68651945f97cp-57 },
	{ 0x1.404308686a7e4p-2, -0x1.0bcfb6082ce6dp-56 },
	{ 0x1.4618bc21c5ec2p-2, 0x1.f42decdeccf1dp-56 },
	{ 0x1.4be5f957778a1p-2, -0x1.259b35b04813dp-57 },
	{ 0x1.51aad872df82dp-2, 0x1.3927ac19f55e3p-59 },
	{ 0x1.5767717455a6cp-2, 0x1.526adb283660cp-56 },
	{ 0x1.5d1bdbf5809cap-2, 0x1.4236383dc7fe1p-56 },
	{ 0x1.62c82f2b9c795p-2, 0x1.7b7af915300e5p-57 },
};
/* atan(i/64), i = 0..64, as hi + lo */
static const double atan_tab[65][2] = {
	{ 0x0.0p+0, 0x0.0p+0 },
	{ 0x1.fff555bbb729bp-7, -0x1.220c39d4dff50p-61 },
	{ 0x1.ffd55bba97625p-6, -0x1.5ec431444912cp-60 },
	{ 0x1.7fb818430da2ap-5, -0x1.86ef8f794f105p-63 },
	{ 0x1.ff55bb72cfdeap-5, -0x1.c934d86d23f1dp-60 },
	{ 0x1.3f59f0e7c559dp-4, 0x1.ac4ce285df847p-58 },
	{ 0x1.7ee182602f10fp-4, -0x1.cfb654c0c3d98p-58 },
	{ 0x1.be39ebe6f07c3p-4, 0x1.f7b8f29a05987p-58 },
	{ 0x1.fd5ba9aac2f6ep-4, -0x1.cd37686760c17p-59 },
	{ 0x1.1e1fafb043727p-3, -0x1.b485914dacf8cp-59 },
	{ 0x1.3d6eee8c6626cp-3, 0x1.61a3b0ce9281bp-57 },
	{ 0x1.5c9811e3ec26ap-3, -0x1.054ab2c010f3dp-58 },
	{ 0x1.7b97b4bce5b02p-3, 0x1.347b0b4f881cap-58 },
	{ 0x1.9a6a8e96c8626p-3, 0x1.cf601e7b4348ep-59 },
	{ 0x1.b90d7529260a2p-3, 0x1.17b10d2e0e5abp-61 },
	{ 0x1.d77d5df205736p-3, 0x1.c648d1534597ep-57 },
	{ 0x1.f5b75f92c80ddp-3, 0x1.8ab6e3cf7afbdp-57 },
	{ 0x1.09dc597d86362p-2, 0x1.62e47390cb865p-56 },
	{ 0x1.18bf5a30bf178p-2, 0x1.30ca4748b1bf9p-57 },
	{ 0x1.278372057ef46p-2, -0x1.077cdd36dfc81p-56 },
	{ 0x1.362773707ebccp-2, -0x1.963a544b672d8p-57 },
	{ 0x1.44aa436c2af0ap-2, -0x1.5d5e43c55b3bap-56 },
	{ 0x1.530ad9951cd4ap-2, -0x1.2566480884082p-57 },
	{ 0x1.614840309cfe2p-2, -0x1.a725715711f00p-56 },
	{ 0x1.6f61941e4def1p-2, -0x1.c63aae6f6e918p-56 },
	{ 0x1.7d5604b63b3f7p-2, 0x1.69c885c2b249ap-56 },
	{ 0x1.8b24d394a1b25p-2, 0x1.b6d0ba3748fa8p-56 },
	{ 0x1.98cd5454d6b18p-2, 0x1.9e6c988fd0a77p-56 },
	{ 0x1.a64eec3cc23fdp-2, -0x1.24dec1b50b7ffp-56 },
	{ 0x1.b3a911da65c6cp-2, 0x1.ae187b1ca5040p-56 },
	{ 0x1.c0db4c94ec9f0p-2, -0x1.cc1ce70934c34p-56 },
	{ 0x1.cde53432c1351p-2, -0x1.a2cfa4418f1adp-56 },
	{ 0x1.dac670561bb4fp-2, 0x1.a2b7f222f65e2p-56 },
	{ 0x1.e77eb7f175a34p-2, 0x1.0e53dc1bf3435p-56 },
	{ 0x1.f40dd0b541418p-2, -0x1.a3992dc382a23p-57 },
	{ 0x1.0039c73c1a40cp-1, -0x1.b32c949c9d593p-55 },
	{ 0x1.0657e94db30d0p-1, -0x1.d5b495f6349e6p-56 },
	{ 0x1.0c6145b5b43dap-1, 0x1.974fa13b5404fp-58 },
	{ 0x1.1255d9bfbd2a9p-1, -0x1.2bdaee1c0ee35p-58 },
	{ 0x1.1835a88be7c13p-1, 0x1.c621cec00c301p-55 },
	{ 0x1.1e00babdefeb4p-1, -0x1.928df287a668fp-58 },
	{ 0x1.23b71e2cc9e6ap-1, 0x1.c421c9f38224ep-57 },
	{ 0x1.2958e59308e31p-1, -0x1.09e73b0c6c087p-56 },
	{ 0x1.2ee628406cbcap-1, 0x1.c5d5e9ff0cf8dp-55 },
	{ 0x1.345f01cce37bbp-1, 0x1.1021137c71102p-55 },
	{ 0x1.39c391cd4171ap-1, -0x1.2304331d8bf46p-55 },
	{ 0x1.3f13fb89e96f4p-1, 0x1.ecf8b492644f0p-56 },
	{ 0x1.445065b795b56p-1, -0x1.f76d0163f79c8p-56 },
	{ 0x1.4978fa3269ee1p-1, 0x1.2419a87f2a458p-56 },
	{ 0x1.4e8de5bb6ec04p-1, 0x1.4a33dbeb3796cp-55 },
	{ 0x1.538f57b89061fp-1, -0x1.1bb74abda520cp-55 },
	{ 0x1.587d81f732fbbp-1, -0x1.5e5c9d8c5a950p-56 },
	{ 0x1.5d58987169b18p-1, 0x1.0028e4bc5e7cap-57 },
	{ 0x1.6220d115d7b8ep-1, -0x1.2b785350ee8c1p-57 },
	{ 0x1.66d663923e087p-1, -0x1.6ea6febe8bbbap-56 },
	{ 0x1.6b798920b3d99p-1, -0x1.a80386188c50ep-55 },
	{ 0x1.700a7c5784634p-1, -0x1.8c34d25aadef6p-56 },
	{ 0x1.748978fba8e0fp-1, 0x1.7b2a6165884a1p-59 },
	{ 0x1.78f6bbd5d315ep-1, 0x1.406a089803740p-55 },
	{ 0x1.7d528289fa093p-1, 0x1.560821e2f3aa9p-55 },
	{ 0x1.819d0b7158a4dp-1, -0x1.bf76229d3b917p-56 },
	{ 0x1.85d69576cc2c5p-1, 0x1.6b66e7fc8b8c3p-57 },
	{ 0x1.89ff5ff57f1f8p-1, -0x1.55b9a5e177a1bp-55 },
	{ 0x1.8e17aa99cc05ep-1, -0x1.ec182ab042f61p-56 },
	{ 0x1.921fb54442d18p-1, 0x1.1a62633145c07p-55 },
};
/* 128/j, j = 90..181, rounded (log's reciprocals: only the rounding's size matters) */
static const double inv_tab[92] = {
	0x1.6c16c16c16c17p+0, 0x1.6816816816817p+0, 0x1.642c8590b2164p+0, 0x1.6058160581606p+0,
	0x1.5c9882b931057p+0, 0x1.58ed2308158edp+0, 0x1.5555555555555p+0, 0x1.51d07eae2f815p+0,
	0x1.4e5e0a72f0539p+0, 0x1.4afd6a052bf5bp+0, 0x1.47ae147ae147bp+0, 0x1.446f86562d9fbp+0,
	0x1.4141414141414p+0, 0x1.3e22cbce4a902p+0, 0x1.3b13b13b13b14p+0, 0x1.3813813813814p+0,
	0x1.3521cfb2b78c1p+0, 0x1.323e34a2b10bfp+0, 0x1.2f684bda12f68p+0, 0x1.2c9fb4d812ca0p+0,
	0x1.29e4129e4129ep+0, 0x1.27350b8812735p+0, 0x1.2492492492492p+0, 0x1.21fb78121fb78p+0,
	0x1.1f7047dc11f70p+0, 0x1.1cf06ada2811dp+0, 0x1.1a7b9611a7b96p+0, 0x1.1811811811812p+0,
	0x1.15b1e5f75270dp+0, 0x1.135c81135c811p+0, 0x1.1111111111111p+0, 0x1.0ecf56be69c90p+0,
	0x1.0c9714fbcda3bp+0, 0x1.0a6810a6810a7p+0, 0x1.0842108421084p+0, 0x1.0624dd2f1a9fcp+0,
	0x1.0410410410410p+0, 0x1.0204081020408p+0, 0x1.0000000000000p+0, 0x1.fc07f01fc07f0p-1,
	0x1.f81f81f81f820p-1, 0x1.f44659e4a4271p-1, 0x1.f07c1f07c1f08p-1, 0x1.ecc07b301ecc0p-1,
	0x1.e9131abf0b767p-1, 0x1.e573ac901e574p-1, 0x1.e1e1e1e1e1e1ep-1, 0x1.de5d6e3f8868ap-1,
	0x1.dae6076b981dbp-1, 0x1.d77b654b82c34p-1, 0x1.d41d41d41d41dp-1, 0x1.d0cb58f6ec074p-1,
	0x1.cd85689039b0bp-1, 0x1.ca4b3055ee191p-1, 0x1.c71c71c71c71cp-1, 0x1.c3f8f01c3f8f0p-1,
	0x1.c0e070381c0e0p-1, 0x1.bdd2b899406f7p-1, 0x1.bacf914c1bad0p-1, 0x1.b7d6c3dda338bp-1,
	0x1.b4e81b4e81b4fp-1, 0x1.b2036406c80d9p-1, 0x1.af286bca1af28p-1, 0x1.ac5701ac5701bp-1,
	0x1.a98ef606a63bep-1, 0x1.a6d01a6d01a6dp-1, 0x1.a41a41a41a41ap-1, 0x1.a16d3f97a4b02p-1,
	0x1.9ec8e951033d9p-1, 0x1.9c2d14ee4a102p-1, 0x1.999999999999ap-1, 0x1.970e4f80cb872p-1,
	0x1.948b0fcd6e9e0p-1, 0x1.920fb49d0e229p-1, 0x1.8f9c18f9c18fap-1, 0x1.8d3018d3018d3p-1,
	0x1.8acb90f6bf3aap-1, 0x1.886e5f0abb04ap-1, 0x1.8618618618618p-1, 0x1.83c977ab2beddp-1,
	0x1.8181818181818p-1, 0x1.7f405fd017f40p-1, 0x1.7d05f417d05f4p-1, 0x1.7ad2208e0ecc3p-1,
	0x1.78a4c8178a4c8p-1, 0x1.767dce434a9b1p-1, 0x1.745d1745d1746p-1, 0x1.724287f46debcp-1,
	0x1.702e05c0b8170p-1, 0x1.6e1f76b4337c7p-1, 0x1.6c16c16c16c17p-1, 0x1.6a13cd1537290p-1,
};
/* 2/pi in 32-bit words: word i holds the bits of weight 2^-(32i+1) .. 2^-(32i+32) */
static const uint32_t two_over_pi[44] = {
	0xa2f9836e, 0x4e441529, 0xfc2757d1, 0xf534ddc0, 0xdb629599, 0x3c439041,
	0xfe5163ab, 0xdebbc561, 0xb7246e3a, 0x424dd2e0, 0x06492eea, 0x09d1921c,
	0xfe1deb1c, 0xb129a73e, 0xe88235f5, 0x2ebb4484, 0xe99c7026, 0xb45f7e41,
	0x3991d639, 0x835339f4, 0x9c845f8b, 0xbdf9283b, 0x1ff897ff, 0xde05980f,
	0xef2f118b, 0x5a0a6d1f, 0x6d367ecf, 0x27cb09b7, 0x4f463f66, 0x9e5fea2d,
	0x7527bac7, 0xebe5f17b, 0x3d0739f7, 0x8a5292ea, 0x6bfb5fb1, 0x1f8d5d08,
	0x56033046, 0xfc7b6bab, 0xf0cfbc20, 0x9af4361d, 0xa9e39161, 0x5ee61b08,
	0x6599855f, 0x14a06840,
};
static const double PIO2_1 = 0x1.921fb54400000p+0; /* 1.5707963267341256142 */
static const double PIO2_2 = 0x1.0b4611a600000p-34; /* 6.0771005063039659766e-11 */
static const double PIO2_3 = 0x1.3198a2e037073p-69; /* 2.0222662487959507324e-21 */
static const double PIO2_HI = 0x1.921fb54442d18p+0; /* 1.570796326794896558 */
static const double PIO2_LO = 0x1.1a62633145c07p-54; /* 6.1232339957367658861e-17 */
static const double PI_HI = 0x1.921fb54442d18p+1; /* 3.141592653589793116 */
static const double PI_LO = 0x1.1a62633145c07p-53; /* 1.2246467991473531772e-16 */
static const double TWO_OVER_PI = 0x1.45f306dc9c883p-1; /* 0.63661977236758134308 */
static const double LN2_HI = 0x1.62e42fefa3800p-1; /* 0.69314718055989033019 */
static const double LN2_LO = 0x1.ef35793c76730p-45; /* 5.4979230187083711747e-14 */
static const double LN2_64_HI = 0x1.62e42fefa0000p-7; /* 0.010830424696223417413 */
static const double LN2_64_LO = 0x1.cf79abc9e3b3ap-46; /* 2.5728046223276689502e-14 */
static const double INV_LN2_64 = 0x1.71547652b82fep+6; /* 92.332482616893658071 */

/* ---- double-double building blocks ---- */

static inline uint64_t dbits(double x)
{
	uint64_t u;
	memcpy(&u, &x, sizeof u);
	return u;
}

static inline double bits_d(uint64_t u)
{
	double x;
	memcpy(&x, &u, sizeof x);
	return x;
}

/* s + e = a + b exactly */
static inline void two_sum(double a, double b, double *s, double *e)
{
	double x = a + b, bv = x - a, av = x - bv;
	*s = x;
	*e = (a - av) + (b - bv);
}

/* s + e = a + b exactly, given |a| >= |b| (or a == 0) */
static inline void fast_two_sum(double a, double b, double *s, double *e)
{
	double x = a + b;
	*s = x;
	*e = b - (x - a);
}

/* hi + lo = a exactly, each half with at most 26 significant bits; |a| < 2^996 */
static inline void vsplit(double a, double *hi, double *lo)
{
	double c = 134217729.0 * a; /* 2^27 + 1 */
	*hi = c - (c - a);
	*lo = a - *hi;
}

/* p + e = a * b exactly (barring underflow); |a|, |b| < 2^996 */
static inline void two_prod(double a, double b, double *p, double *e)
{
	double ah, al, bh, bl;
	vsplit(a, &ah, &al);
	vsplit(b, &bh, &bl);
	*p = a * b;
	*e = ((ah * bh - *p) + ah * bl + al * bh) + al * bl;
}

/* two_prod when b has at most 26 significant bits (a table constant, i/8):
 * only a is split */
static inline void two_prod_short(double a, double b, double *p, double *e)
{
	double ah, al;
	vsplit(a, &ah, &al);
	*p = a * b;
	*e = (ah * b - *p) + al * b;
}

/* p + e = a * a exactly */
static inline void two_sqr(double a, double *p, double *e)
{
	double ah, al;
	vsplit(a, &ah, &al);
	*p = a * a;
	*e = ((ah * ah - *p) + 2 * ah * al) + al * al;
}

/* round to the nearest integer, |x| < 2^51 */
static inline double rint_small(double x)
{
	const double magic = 0x1.8p52;
	return (x + magic) - magic;
}

static inline double poly(const double *c, int n, double z)
{
	double r = c[n - 1];
	for (int i = n - 2; i >= 0; i--)
		r = r * z + c[i];
	return r;
}

/* ---- sin, cos, tan ---- */

/* the 64 bits of p (little-endian 32-bit limbs) starting at bit `at` */
static uint64_t get64(const uint32_t *p, int at)
{
	int w = at / 32, b = at % 32;
	uint64_t lo = p[w] | (uint64_t)p[w + 1] << 32;
	if (b == 0)
		return lo;
	return lo >> b | (uint64_t)p[w + 2] << (64 - b);
}

/*
 * Payne-Hanek: |x| >= 2^19 finite. Returns n (mod 4) with x = n pi/2 + r,
 * r = *rh + *rl, |r| <= pi/4. x = m 2^e (m a 53-bit integer); the words of
 * 2/pi whose product with x is a multiple of 4 are skipped, the next 8 words
 * (256 bits) multiplied by m in exact integer arithmetic: the integer part
 * gives n, the fraction's top 192 bits (of >= 223) give r: >= 120 bits
 * survive the worst cancellation of any double (|r| about 2^-61).
 */
static int rem_pio2_large(double x, double *rh, double *rl)
{
	uint64_t ix = dbits(x);
	int e = (int)(ix >> 52 & 0x7ff) - 1075;
	uint64_t m = (ix & 0xfffffffffffffull) | 1ull << 52;
	uint32_t ml = (uint32_t)m, mh = (uint32_t)(m >> 32);
	int s = e >= 2 ? (e - 2) / 32 : 0;
	uint64_t a[8], b[8];
	for (int k = 0; k < 8; k++) {
		uint32_t w = two_over_pi[s + 7 - k]; /* little-endian: limb k */
		a[k] = (uint64_t)w * ml;
		b[k] = (uint64_t)w * mh;
	}
	uint32_t p[12]; /* two zero limbs above the product: get64 may read them */
	uint64_t acc = 0;
	for (int c = 0; c < 10; c++) {
		if (c < 8)
			acc += (uint32_t)a[c];
		if (c >= 1 && c <= 8)
			acc += (a[c - 1] >> 32) + (uint32_t)b[c - 1];
		if (c >= 2)
			acc += b[c - 2] >> 32;
		p[c] = (uint32_t)acc;
		acc >>= 32;
	}
	p[10] = p[11] = 0;
	int B = 32 * (s + 8) - e; /* the bit of weight 2^0 */
	int n = (int)(get64(p, B) & 3);
	/* the fraction's top 192 bits f[0] (most significant) .. f[2] */
	uint64_t f[3] = { get64(p, B - 64), get64(p, B - 128), get64(p, B - 192) };
	double sign = 1;
	if (f[0] >> 63) { /* fraction >= 1/2: r = f - 1, negative */
		n++;
		sign = -1;
		f[2] = ~f[2] + 1;
		f[1] = ~f[1] + (f[2] == 0);
		f[0] = ~f[0] + (f[2] == 0 && f[1] == 0);
	}
	int lz = 0; /* normalise: the top bit of f[0] set (lz < 128: |r| >> 2^-128) */
	while (f[0] == 0 && lz < 128) {
		f[0] = f[1];
		f[1] = f[2];
		f[2] = 0;
		lz += 64;
	}
	if (f[0] == 0) {
		*rh = *rl = 0;
		return n & 3;
	}
	while (!(f[0] >> 63)) {
		f[0] = f[0] << 1 | f[1] >> 63;
		f[1] = f[1] << 1 | f[2] >> 63;
		f[2] <<= 1;
		lz++;
	}
	double hi = (double)(f[0] >> 11) * 0x1p-53;                       /* 53 bits, exact */
	double lo = (double)((f[0] & 0x7ff) << 42 | f[1] >> 22) * 0x1p-106; /* the next 53 */
	double scale = bits_d((uint64_t)(1023 - lz) << 52);               /* 2^-lz */
	hi *= scale;
	lo *= scale;
	double ph, pl;
	two_prod(hi, PIO2_HI, &ph, &pl);
	pl += hi * PIO2_LO + lo * PIO2_HI;
	fast_two_sum(ph, pl, rh, rl);
	*rh *= sign;
	*rl *= sign;
	return n & 3;
}

/* x finite, |x| > pi/4: n (mod 4) and r = *rh + *rl with x = n pi/2 + r */
static int rem_pio2(double x, double *rh, double *rl)
{
	if (fabs(x) >= 0x1p19) {
		if (x < 0) {
			int n = rem_pio2_large(-x, rh, rl);
			*rh = -*rh;
			*rl = -*rl;
			return -n & 3;
		}
		return rem_pio2_large(x, rh, rl);
	}
	/* Cody-Waite: k PIO2_1 and k PIO2_2 are exact (33-bit constants, |k| < 2^19) */
	double k = rint_small(x * TWO_OVER_PI);
	double r1 = x - k * PIO2_1; /* exact: Sterbenz */
	double s, e, h, l;
	two_sum(r1, -(k * PIO2_2), &s, &e);
	two_sum(s, e - k * PIO2_3, &h, &l);
	fast_two_sum(h, l, rh, rl);
	return (int)k & 3;
}

/* sin(x + y), |x| <= pi/4 + a little, |y| <= ulp(x) */
static double ksin(double x, double y)
{
	double z = x * x, v = z * x;
	return x + (v * poly(sin_c, 7, z) + (y - 0.5 * z * y));
}

/* cos(x + y), the same domain: 1 - x^2/2 with x^2 exact and 1 - x^2/2's
 * rounding error carried */
static double kcos(double x, double y)
{
	double z, ze;
	two_sqr(x, &z, &ze);
	double hz = 0.5 * z, w = 1.0 - hz;
	double c = (1.0 - w) - hz; /* exact (Fast2Sum) */
	return w + (c + ((z * z * poly(cos_c, 7, z) - 0.5 * ze) - x * y));
}

#define PIO4 0x1.921fb54442d18p-1

double xm_sin(double x)
{
	double a = fabs(x), rh, rl;
	if (a < 0x1p-26)
		return x; /* also +-0, subnormals */
	if (a <= PIO4)
		return ksin(x, 0);
	if (!(a < INFINITY))
		return x - x; /* NaN for NaN and +-inf */
	switch (rem_pio2(x, &rh, &rl)) {
	case 0: return ksin(rh, rl);
	case 1: return kcos(rh, rl);
	case 2: return -ksin(rh, rl);
	default: return -kcos(rh, rl);
	}
}

double xm_cos(double x)
{
	double a = fabs(x), rh, rl;
	if (a < 0x1p-27)
		return 1.0;
	if (a <= PIO4)
		return kcos(x, 0);
	if (!(a < INFINITY))
		return x - x;
	switch (rem_pio2(x, &rh, &rl)) {
	case 0: return kcos(rh, rl);
	case 1: return -ksin(rh, rl);
	case 2: return -kcos(rh, rl);
	default: return ksin(rh, rl);
	}
}

void xm_sincos(double x, double *s, double *c)
{
	double a = fabs(x), rh, rl;
	if (a <= PIO4) {
		*s = a < 0x1p-26 ? x : ksin(x, 0);
		*c = a < 0x1p-27 ? 1.0 : kcos(x, 0);
		return;
	}
	if (!(a < INFINITY)) {
		*s = *c = x - x;
		return;
	}
	int n = rem_pio2(x, &rh, &rl);
	double sr = ksin(rh, rl), cr = kcos(rh, rl);
	switch (n) {
	case 0: *s = sr; *c = cr; break;
	case 1: *s = cr; *c = -sr; break;
	case 2: *s = -sr; *c = -cr; break;
	default: *s = -cr; *c = sr; break;
	}
}

double xm_tan(double x)
{
	double a = fabs(x), rh = x, rl = 0;
	int n = 0;
	if (a < 0x1p-27)
		return x;
	if (!(a < INFINITY))
		return x - x;
	if (a > PIO4)
		n = rem_pio2(x, &rh, &rl);
	double sr = ksin(rh, rl), cr = kcos(rh, rl);
	return n & 1 ? -cr / sr : sr / cr;
}

/* ---- atan, atan2, asin, acos ---- */

/* *rh + *rl = c - (ah + al) for the constant c = chi + clo */
static inline void dd_sub_from(double chi, double clo, double ah, double al, double *rh, double *rl)
{
	double s, e;
	two_sum(chi, -ah, &s, &e);
	fast_two_sum(s, e + (clo - al), rh, rl);
}

/*
 * atan(n / d) as a double-double *rh + *rl, for 0 <= n <= d, n and d
 * doubles with 2^-300 <= d <= 2^300 (n may be 0 or tiny). Below 3.5/64 the
 * quotient t = n/d itself, with its remainder (exact), goes into the
 * polynomial. Above, with c = i/64 nearest n/d: atan(n/d) = atan(c) +
 * atan(t), t = (n - c d) / (d + c n), |t| <= 1/128; n - c d is exact (c d
 * as a double-double, then Sterbenz) and t's two roundings (the
 * denominator's and the quotient's) cost at most 2^-59, a quarter of an ulp
 * of a result >= atan(3.5/64).
 */
static void atan_ratio(double n, double d, double *rh, double *rl)
{
	double z0 = n / d;
	int i = (int)(z0 * 64 + 0.5); /* 0 .. 64 */
	if (i < 4) {
		double u, ue;
		two_prod(z0, d, &u, &ue);
		double tl = ((n - u) - ue) / d, z = z0 * z0;
		fast_two_sum(z0, z0 * z * poly(atan_c, 6, z) + (tl - tl * z), rh, rl);
		return;
	}
	double c = i * 0x1p-6, p, pe;
	two_prod_short(d, c, &p, &pe);
	double D = d + c * n;
	double th = (n - p) / D, tl = -pe / D; /* n - p exact */
	double z = th * th;
	double lo = th * z * poly(atan_s, 3, z) + tl;
	fast_two_sum(atan_tab[i][0], th + (atan_tab[i][1] + lo), rh, rl);
}

double xm_atan(double x)
{
	double a = fabs(x), rh, rl;
	if (!(a <= 0x1p60)) /* also NaN */
		return a != a ? x + x : x > 0 ? PIO2_HI + PIO2_LO : -PIO2_HI - PIO2_LO;
	if (a < 0x1p-27)
		return x;
	if (a <= 1) {
		atan_ratio(a, 1, &rh, &rl);
	} else {
		atan_ratio(1, a, &rh, &rl);
		dd_sub_from(PIO2_HI, PIO2_LO, rh, rl, &rh, &rl);
	}
	return x < 0 ? -rh : rh;
}

double xm_atan2(double y, double x)
{
	double ay = fabs(y), ax = fabs(x), rh, rl;
	if (ay > 0 && ax > 0 && ay < INFINITY && ax < INFINITY)
		goto finite;
	if (x != x || y != y)
		return x + y;
	if (ay == 0) /* atan2(+-0, x): +-0 for x > 0 or +0, +-pi for x < 0 or -0 */
		return signbit(x) ? copysign(PI_HI + PI_LO, y) : y;
	if (ax == 0)
		return copysign(PIO2_HI + PIO2_LO, y);
	if (ax == INFINITY || ay == INFINITY) {
		double r;
		if (ax == INFINITY && ay == INFINITY)
			r = x > 0 ? 0.5 * (PIO2_HI + PIO2_LO) : 0x1.2d97c7f3321d2p+1; /* 3 pi/4 */
		else if (ay == INFINITY)
			r = PIO2_HI + PIO2_LO;
		else
			r = x > 0 ? 0 : PI_HI + PI_LO;
		return copysign(r, y);
	}
finite:;
	int swap = ay > ax;
	double n = swap ? ax : ay, d = swap ? ay : ax;
	if (n < d * 0x1p-60) {
		/* atan(z) = z to the last bit: z rounded once (it may be subnormal) */
		rh = n / d;
		rl = 0;
	} else {
		/* a power of two brings d into atan_ratio's range; the quotient is unchanged */
		double sc = d > 0x1p300 ? 0x1p-600 : d < 0x1p-300 ? 0x1p600 : 1;
		atan_ratio(n * sc, d * sc, &rh, &rl);
	}
	if (swap)
		dd_sub_from(PIO2_HI, PIO2_LO, rh, rl, &rh, &rl);
	if (x < 0)
		dd_sub_from(PI_HI, PI_LO, rh, rl, &rh, &rl);
	return y < 0 ? -rh : rh;
}

/*
 * asin(s + sl) - (s + sl) for 0 <= s <= 1/2 (z = s^2, near enough): the
 * odd polynomial's tail s^3 P(z) plus the first-order effect of sl
 */
static inline double asin_tail(double s, double sl, double z)
{
	return s * z * poly(asin_c, 13, z) + sl;
}

/* For 1/2 < a <= 1: s + sl = sqrt((1 - a) / 2) and z = (1 - a) / 2, with
 * asin(a) = pi/2 - 2 asin(s) and acos(a) = 2 asin(s) */
static inline void half_angle(double a, double *s, double *sl, double *z)
{
	double zz = (1 - a) * 0.5; /* exact: Sterbenz, then a power of two */
	double r = sqrt(zz), q, qe;
	two_sqr(r, &q, &qe);
	*s = r;
	*sl = r > 0 ? ((zz - q) - qe) / (2 * r) : 0;
	*z = zz;
}

double xm_asin(double x)
{
	double a = fabs(x), rh, rl;
	if (!(a <= 1))
		return (x - x) / (x - x); /* NaN, also for NaN */
	if (a < 0x1p-26)
		return x;
	if (a <= 0.5) {
		double z = a * a;
		rh = a + a * z * poly(asin_c, 13, z);
	} else {
		double s, sl, z;
		half_angle(a, &s, &sl, &z);
		double t = asin_tail(s, sl, z);
		dd_sub_from(PIO2_HI, PIO2_LO, 2 * s, 2 * t, &rh, &rl);
	}
	return x < 0 ? -rh : rh;
}

double xm_acos(double x)
{
	double a = fabs(x), rh, rl;
	if (!(a <= 1))
		return (x - x) / (x - x);
	if (a < 0x1p-60)
		return PIO2_HI + PIO2_LO;
	if (a <= 0.5) { /* pi/2 - asin(x) */
		double z = a * a, t = a * z * poly(asin_c, 13, z);
		if (x < 0)
			a = -a, t = -t;
		dd_sub_from(PIO2_HI, PIO2_LO, a, t, &rh, &rl);
		return rh;
	}
	double s, sl, z;
	half_angle(a, &s, &sl, &z);
	double t = asin_tail(s, sl, z);
	if (x > 0)
		return 2 * s + 2 * t; /* 2 asin(s) */
	dd_sub_from(PI_HI, PI_LO, 2 * s, 2 * t, &rh, &rl); /* pi - 2 asin(s) */
	return rh;
}

/* ---- exp, log, pow ---- */

/* exp(xh + xl), -746 < xh < 710, |xl| <= ulp(xh): overflows to inf and
 * underflows to subnormals and 0 on its own */
static inline double exp_core(double xh, double xl)
{
	double kd = rint_small(xh * INV_LN2_64);
	int n = (int)kd, j = n & 63, k = (n - j) / 64;
	/* kd LN2_64_HI exact (36-bit constant, |kd| < 2^17); xh - it exact (Sterbenz) */
	double r = ((xh - kd * LN2_64_HI) - kd * LN2_64_LO) + xl;
	double p = r + (0.5 * r * r + r * r * r * poly(exp_c, 4, r));
	double th = exp_tab[j][0], tl = exp_tab[j][1];
	double s = th + (th * p + tl * (1 + p));
	if ((unsigned)(k + 1000) <= 2000u)
		return s * bits_d((uint64_t)(k + 1023) << 52);
	if (k > 1000)
		return s * bits_d((uint64_t)(k - 1 + 1023) << 52) * 2.0;
	return s * bits_d((uint64_t)(k + 1000 + 1023) << 52) * 0x1p-1000;
}

double xm_exp(double x)
{
	if (x != x)
		return x + x;
	if (x > 0x1.62e42fefa39efp+9)
		return 0x1p1023 * 2.0; /* inf, with the overflow flag */
	if (x < -0x1.74910d52d3052p+9)
		return 0x1p-1022 * 0x1p-1022; /* 0, with the underflow flag */
	if (fabs(x) < 0x1p-54)
		return 1.0 + x;
	return exp_core(x, 0);
}

/* log(x) as a double-double *rh + *rl, x > 0 finite; relative error below
 * 2^-68 */
/* x = 2^k m with m in [sqrt 1/2, sqrt 2] (x > 0 finite, subnormal too):
 * m exact, k into *kp */
static inline double log_reduce(double x, int *kp)
{
	uint64_t ix = dbits(x);
	int k = 0;
	if (ix >> 52 == 0) { /* subnormal */
		x *= 0x1p54;
		ix = dbits(x);
		k = -54;
	}
	k += (int)(ix >> 52) - 1023;
	double m = bits_d((ix & 0xfffffffffffffull) | 0x3ffull << 52); /* [1, 2) */
	if (m > 0x1.6a09e667f3bcdp+0) { /* sqrt 2: m into [sqrt 1/2, sqrt 2] */
		m *= 0.5;
		k++;
	}
	*kp = k;
	return m;
}

static inline void log_core(double x, double *rh, double *rl)
{
	int k;
	double m = log_reduce(x, &k);
	int j = (int)(m * 128 + 0.5);
	double F = j * 0x1p-7, f = m - F, inv = inv_tab[j - 90]; /* f exact */
	/* q = f / F: a product with 1/F rounded, then the remainder (exact) times it */
	double qh = f * inv, a, ae;
	two_prod_short(qh, F, &a, &ae);
	double ql = ((f - a) - ae) * inv;
	/* log1p(q) = q - q^2/2 + q^3 L(q), q^2 exact */
	double s, se, h, e;
	two_sqr(qh, &s, &se);
	two_sum(qh, -0.5 * s, &h, &e);
	double lo = e + (ql - 0.5 * se - qh * ql + qh * s * poly(log1p_c, 6, qh));
	/* + k ln2 + log F */
	double kd = k, u, ue, t, te;
	/* Fast2Sum applies: |k ln2| >= ln2 > |log F| unless k = 0, and |log F| >=
	 * log(129/128) > |h| unless F = 1 (then log F = 0) */
	fast_two_sum(kd * LN2_HI, log_tab[j - 90][0], &u, &ue);
	fast_two_sum(u, h, &t, &te);
	lo += ue + te + (kd * LN2_LO + log_tab[j - 90][1]);
	fast_two_sum(t, lo, rh, rl);
}

double xm_log(double x)
{
	double rh, rl;
	if (x != x)
		return x + x;
	if (x < 0)
		return (x - x) / (x - x);
	if (x == 0)
		return -1 / (x * x); /* -inf, with the divide-by-zero flag */
	if (x == INFINITY)
		return x;
	if (x == 1)
		return 0;
	log_core(x, &rh, &rl);
	return rh;
}

/*
 * LITE POW: log(x) in one double (x > 0 finite, x != 1): log_core's
 * reduction (x = 2^k m, m = F (1 + q) with F = j/128 from the table), its
 * sums rounded once each instead of carried as double-doubles, and
 * log1p(q) to q^6 (|q| < 2^-7.5: the rest is below 2^-55 of q).
 */
static inline double log_lite(double x)
{
	int k;
	double m = log_reduce(x, &k);
	int j = (int)(m * 128 + 0.5);
	double f = m - j * 0x1p-7, q = f * inv_tab[j - 90]; /* f exact */
	double q2 = q * q;
	double l1p = q + (q2 * (q * poly(log1p_c, 4, q) - 0.5));
	double kd = k;
	return (kd * LN2_HI + log_tab[j - 90][0]) + (l1p + (kd * LN2_LO + log_tab[j - 90][1]));
}

double xm_pow_lite(double x, double y)
{
	uint64_t ix = dbits(x), iy = dbits(y) & 0x7fffffffffffffffull;
	/* 0 < x < inf, x != 1, 0 < |y| < 2^20 */
	if (ix - 1 < 0x7fefffffffffffffull && iy - 1 < 0x412fffffffffffffull && x != 1) {
		if (y == 1)
			return x;
		if (y == 2)
			return x * x;
		double z = y * log_lite(x);
		if (z > 709)
			return xm_pow(x, y); /* near overflow: the careful one decides */
		if (z < -744)
			return z < -760 ? 0.0 : xm_pow(x, y);
		return exp_core(z, 0);
	}
	return xm_pow(x, y);
}

/* sign * x^y for x > 0 finite, x != 1, 0 < |y| < 2^64 */
static inline double pow_core(double x, double y, double sign)
{
	double lh, ll, zh, ze, z, zl;
	log_core(x, &lh, &ll);
	two_prod(y, lh, &zh, &ze);
	fast_two_sum(zh, ze + y * ll, &z, &zl);
	if (z > 710)
		return sign * 0x1p1023 * 2.0;
	if (z < -746)
		return sign * 0x1p-1022 * 0x1p-1022;
	return sign * exp_core(z, zl);
}

/* the special values of C99 F.9.4.4, and x < 0 */
static double pow_special(double x, double y)
{
	if (y == 0 || x == 1)
		return 1.0;
	if (x != x || y != y)
		return x + y;
	double ax = fabs(x), ay = fabs(y);
	if (ay == INFINITY) {
		if (ax == 1)
			return 1.0;
		return (ax > 1) == (y > 0) ? INFINITY : 0.0;
	}
	int yint = 0; /* 0: y not an integer, 1: odd, 2: even */
	if (ay >= 0x1p53)
		yint = 2;
	else if (floor(y) == y)
		yint = floor(0.5 * y) == 0.5 * y ? 2 : 1;
	if (x == 0) {
		if (y < 0)
			return yint == 1 ? 1 / x : 1 / (x * x);
		return yint == 1 ? x : 0.0;
	}
	if (ax == INFINITY) {
		if (x > 0)
			return y < 0 ? 0.0 : INFINITY;
		if (y < 0)
			return yint == 1 ? -0.0 : 0.0;
		return yint == 1 ? -INFINITY : INFINITY;
	}
	double sign = 1;
	if (x < 0) {
		if (yint == 0)
			return (x - x) / (x - x);
		if (yint == 1)
			sign = -1;
		x = ax;
	}
	if (x == 1)
		return sign;
	if (ay >= 0x1p64) /* |y log x| >= 2^64 2^-53: far beyond the range */
		return (x > 1) == (y > 0) ? sign * 0x1p1023 * 2.0 : sign * 0x1p-1022 * 0x1p-1022;
	return pow_core(x, y, sign);
}

double xm_pow(double x, double y)
{
	uint64_t ix = dbits(x), iy = dbits(y) & 0x7fffffffffffffffull;
	/* the common case first: 0 < x < inf, x != 1, 0 < |y| < 2^64 */
	if (ix - 1 < 0x7fefffffffffffffull && iy - 1 < 0x43efffffffffffffull && x != 1) {
		if (y == 1)
			return x;
		if (y == 2) /* fall-off 2: one correctly rounded product */
			return x * x;
		return pow_core(x, y, 1.0);
	}
	return pow_special(x, y);
}
