// Checklist items 1-4 (digest section 10): the device list, its event, the devices' identity and
// the BAL shared by several clients.
using System;
using System.Collections;
using System.Threading;
using Ixxat.Vci3;
using Ixxat.Vci3.Bal.Can;
using NUnit.Framework;

namespace Canemu.Tests
{
  [TestFixture]
  public class DeviceTests
  {
    [Test]
    public void Item01_AddAndRemoveOfAnAdapterSignalTheAssignedEvent()
    {
      using (new Daemon(Daemon.TwoAdapters))
      using (var manager = VciServer.GetDeviceManager())
      using (var list = manager.GetDeviceList())
      using (var other = manager.GetDeviceList())
      {
        var auto = new AutoResetEvent(false);
        var manual = new ManualResetEvent(false);
        list.AssignEvent(auto);
        other.AssignEvent(manual);
        Assert.IsFalse(auto.WaitOne(300), "no change, no signal");
        Assert.IsFalse(manual.WaitOne(0));
        string name = Emulator.CreateDevice("can0", "plugged");
        Assert.AreEqual("plugged", name);
        Assert.IsTrue(auto.WaitOne(5000), "signalled on arrival");
        Assert.IsTrue(manual.WaitOne(5000), "every assigned event");
        Assert.AreEqual(3, T.Devices().Count);
        manual.Reset();
        Emulator.RemoveDevice("plugged");
        Assert.IsTrue(auto.WaitOne(5000), "signalled on removal");
        Assert.IsTrue(manual.WaitOne(5000));
        Assert.AreEqual(2, T.Devices().Count);
        Assert.IsFalse(auto.WaitOne(300), "once per change");
      }
    }

    [Test]
    public void Item02_CurrentIsANewObjectEveryTimeMoveNextEndsAndResetRewinds()
    {
      using (new Daemon(Daemon.TwoAdapters))
      using (var list = VciServer.GetDeviceManager().GetDeviceList())
      {
        IEnumerator e = list.GetEnumerator();
        Assert.IsTrue(e.MoveNext());
        var first = (IVciDevice)e.Current;
        var again = (IVciDevice)e.Current;
        Assert.IsFalse(ReferenceEquals(first, again), "a new device object on every read");
        Assert.AreEqual(first.VciObjectId, again.VciObjectId);
        Assert.IsTrue(e.MoveNext());
        var second = (IVciDevice)e.Current;
        Assert.IsFalse(e.MoveNext(), "two adapters, then the end");
        Assert.IsFalse(e.MoveNext());
        e.Reset();
        Assert.IsTrue(e.MoveNext());
        Assert.AreEqual(first.VciObjectId, ((IVciDevice)e.Current).VciObjectId);
        Assert.AreNotEqual(first.VciObjectId, second.VciObjectId);
        // foreach works on the list as on any IEnumerable.
        int n = 0;
        foreach (IVciDevice d in list) { n++; d.Dispose(); }
        Assert.AreEqual(2, n);
      }
    }

    [Test]
    public void Item03_IdentityClassHardwareIdAndEquipment()
    {
      using (new Daemon(Daemon.WithLin))
      {
        var alpha = T.Device("alpha");
        var beta = T.Device("beta");
        var gamma = T.Device("gamma");
        Assert.AreEqual(1, alpha.VciObjectId);
        Assert.AreEqual(2, beta.VciObjectId);
        Assert.AreEqual(3, gamma.VciObjectId);
        Assert.AreEqual(new Guid("6A4C1E3B-2C0D-4E7A-9B41-5D3F108E77A2"), alpha.DeviceClass);
        Assert.AreEqual(alpha.DeviceClass, beta.DeviceClass, "one class per adapter type");
        Assert.AreEqual("USB-to-CAN (canemu alpha)", alpha.Description);
        Assert.AreEqual("canemu", alpha.Manufacturer);
        // A boxed Guid whose bytes are the serial number "HW" and six digits.
        object hw = alpha.UniqueHardwareId;
        Assert.IsInstanceOf<Guid>(hw);
        byte[] bytes = ((Guid)hw).ToByteArray();
        Assert.AreEqual('H', (char)bytes[0]);
        Assert.AreEqual('W', (char)bytes[1]);
        for (int i = 2; i < 8; i++) Assert.IsTrue(char.IsDigit((char)bytes[i]), "digit " + i);
        Assert.AreNotEqual(alpha.UniqueHardwareId, beta.UniqueHardwareId);
        Assert.AreEqual(alpha.UniqueHardwareId, T.Device("alpha").UniqueHardwareId, "the same from call to call");
        // One entry per bus connection: CAN (SJA1000), then the LIN controller.
        Assert.AreEqual(1, alpha.Equipment.Length);
        Assert.AreEqual(VciBusType.Can, alpha.Equipment[0].BusType);
        Assert.AreEqual((byte)CanCtrlType.Sja1000, alpha.Equipment[0].ControllerType);
        Assert.AreEqual(2, gamma.Equipment.Length);
        Assert.AreEqual(VciBusType.Lin, gamma.Equipment[1].BusType);
        Assert.IsNotNull(alpha.DriverVersion);
        Assert.IsNotNull(alpha.HardwareVersion);
        using (var bal = gamma.OpenBusAccessLayer())
        {
          Assert.AreEqual(2, bal.Resources.Count);
          Assert.AreEqual(VciBusType.Can, bal.Resources[0].BusType);
          Assert.AreEqual(VciBusType.Lin, bal.Resources[1].BusType);
          Assert.AreEqual(1, bal.Resources[1].BusPort);
          Assert.AreEqual(alpha.DriverVersion.Major, bal.FirmwareVersion.Major);
        }
      }
    }

    [Test]
    public void Item04_TheBalIsOpenedByTwoClientsAtOnce()
    {
      using (new Daemon(Daemon.TwoAdapters))
      using (var one = T.Bal("alpha"))
      using (var two = T.Bal("alpha"))
      using (var a = T.Open<ICanChannel>(one))
      using (var b = T.Open<ICanChannel>(two))
      using (var control = T.Open<ICanControl>(two))
      using (var beta = new Line("beta"))
      {
        a.Initialize(16, 4, false);
        b.Initialize(16, 4, false);
        a.Activate();
        b.Activate();
        control.InitLine(CanOperatingModes.Standard, CanBitrate.Cia500KBit);
        control.StartLine();
        var ra = a.GetMessageReader();
        var rb = b.GetMessageReader();
        beta.Send(T.Msg(0x42, 7));
        T.Step(2);
        Assert.AreEqual(1, T.Drain(ra).Count);
        Assert.AreEqual(1, T.Drain(rb).Count);
        // After the BAL, the device objects may go (chapter 2.3).
        one.Dispose();
        Assert.AreEqual(4, a.GetMessageWriter().Capacity);
      }
    }
  }
}
