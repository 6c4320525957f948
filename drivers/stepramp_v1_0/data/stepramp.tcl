# SPDX-License-Identifier: MIT
# The stepramp driver's BSP hook (see stepramp.mdd): writes the stepramp_axil instances' defines into the BSP's
# xparameters.h --
#   XPAR_STEPRAMP_NUM_INSTANCES
#   XPAR_<INSTANCE>_DEVICE_ID, XPAR_<INSTANCE>_BASEADDR, XPAR_<INSTANCE>_HIGHADDR   (per instance name)
#   XPAR_STEPRAMP_<n>_DEVICE_ID, XPAR_STEPRAMP_<n>_BASEADDR, XPAR_STEPRAMP_<n>_HIGHADDR   (canonical, n = 0, 1, ..)
# so that an application writes stepramp_init(&motor, XPAR_STEPRAMP_0_BASEADDR, ...). C_BASEADDR / C_HIGHADDR
# are the address range the address editor gives the s_axil interface (the core has no address generic).
# UNTESTED in Vitis (not installed where stepramp is developed); sw/tests/test_vitis_driver.py checks the call and
# builds src/ against the xparameters.h it describes.

proc generate {drv_handle} {
  ::hsi::utils::define_include_file $drv_handle "xparameters.h" "STEPRAMP" \
    "NUM_INSTANCES" "DEVICE_ID" "C_BASEADDR" "C_HIGHADDR"
  ::hsi::utils::define_canonical_xpars $drv_handle "xparameters.h" "STEPRAMP" \
    "DEVICE_ID" "C_BASEADDR" "C_HIGHADDR"
}
